"""A localization error that drifts like GNSS, for ``ScenarioParams(localization="drifting")``.

A GNSS or map-matching error is a bias that wanders over seconds to minutes: consecutive frames
share most of it. Per axis (x, y, yaw) the bias is a first-order Gauss-Markov process of standard
deviation sigma (``loc_x``, ``loc_y``, ``loc_yaw``) and time constant tau (``loc_tau``), stepped by
the frames' own timestamps:

    b(t_k) = a_k b(t_{k-1}) + sigma sqrt(1 - a_k^2) w_k,      a_k = exp(-(t_k - t_{k-1}) / tau),

started from its stationary distribution, b(t_0) = sigma w_0; on top of it each frame adds white
noise of ``loc_white`` times sigma. w and the white noise are standard normal draws made for the
whole sequence at once from (seed, CAV): a frame's error is the same whatever frames were computed
before it, in what order or on which worker.
"""
from __future__ import annotations

import functools
import zlib

import numpy as np

DRIFT_STREAM = 0x6472
"""Tags the drift's generator apart from the trials' (``evaluation.scenario.trial_rng``)."""


def drift_error(sigma: np.ndarray, tau: float, white: float, seed: int, cav: str, times: np.ndarray,
                index: int) -> np.ndarray:
    """(dx, dy, dyaw) of frame ``index`` of a sequence with ``times`` (seconds), for the CAV ``cav``:
    the Gauss-Markov bias plus white noise, each axis scaled by ``sigma``."""
    bias, jitter = _unit_series(seed, cav, np.ascontiguousarray(times, dtype=np.float64).tobytes(), float(tau))
    return np.asarray(sigma, dtype=float) * (bias[index] + white * jitter[index])


@functools.lru_cache(maxsize=64)
def _unit_series(seed: int, cav: str, times: bytes, tau: float) -> tuple[np.ndarray, np.ndarray]:
    """The unit-variance Gauss-Markov series and white draws (each (N, 3)) of a sequence's frames."""
    t = np.frombuffer(times, dtype=np.float64)
    rng = np.random.default_rng([seed, DRIFT_STREAM, zlib.crc32(cav.encode("utf-8"))])
    steps, jitter = rng.standard_normal((len(t), 3)), rng.standard_normal((len(t), 3))
    decay = np.exp(-np.maximum(np.diff(t), 0.0) / tau)
    bias = np.empty((len(t), 3))
    if len(t):
        bias[0] = steps[0]
    for k in range(1, len(t)):
        bias[k] = decay[k - 1] * bias[k - 1] + np.sqrt(1.0 - decay[k - 1] ** 2) * steps[k]
    bias.flags.writeable = jitter.flags.writeable = False
    return bias, jitter
