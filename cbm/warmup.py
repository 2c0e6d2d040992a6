"""Compile CBM's numba kernels ahead of the first real call, into numba's on-disk cache.

``cbm.match`` runs numba kernels that are compiled on their first call (seconds) and cached on disk
(``cache=True``: next to the sources, or in ``NUMBA_CACHE_DIR``); later processes load them in a
fraction of a second. ``warm_up`` calls ``match`` on a small synthetic scene once per parameter
variant that reaches a kernel of its own, so that a caller's first real call compiles nothing.

    python -m cbm.warmup      # fill the cache; prints one line per variant, then the total seconds

Run it in a subprocess to fill the cache without holding the caller's interpreter lock (numba's
compiler is mostly Python), then call ``warm_up(VARIANTS[:1])`` in the caller to load the kernels.
"""
from __future__ import annotations

import sys
import time
from collections.abc import Callable, Sequence

import numpy as np

from . import se2
from .params import CBMParams
from .pipeline import match

VARIANTS: tuple[CBMParams, ...] = (
    CBMParams(),
    CBMParams(consensus_rule="paper"),
    CBMParams(consensus=False),
    CBMParams(heading="fold"),
    CBMParams(estimator="least_squares", refine=False),
)
"""The defaults first (what a first frame needs), then one change each: the consensus rule, the
consensus off, the heading handling, the released code's estimator without the re-association."""


def scene(n: int = 30, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(ego boxes, CAV boxes, init) of ``n`` co-visible cars seen by both agents, the CAV's pose
    off by 1 m, 1 m and 2 degrees: enough structure for every stage of ``match`` to run."""
    rng = np.random.default_rng(seed)
    boxes = np.zeros((n, 7))
    boxes[:, :2] = rng.uniform(-30.0, 30.0, (n, 2))
    boxes[:, 2:6] = (0.8, 4.5, 1.9, 1.6)
    boxes[:, 6] = rng.uniform(-np.pi, np.pi, n)
    truth = se2.make(5.0, -3.0, 0.3)
    cav = se2.apply_boxes(se2.inverse(truth), boxes)
    cav[:, :2] += rng.normal(0.0, 0.1, (n, 2))
    return boxes, cav, se2.make(1.0, 1.0, np.radians(2.0)) @ truth


def warm_up(variants: Sequence[CBMParams] = VARIANTS,
            report: Callable[[CBMParams, float], None] | None = None) -> float:
    """Call ``match`` once per variant (``report(variant, seconds)`` after each); the seconds spent."""
    ego, cav, init = scene()
    started = time.perf_counter()
    for params in variants:
        before = time.perf_counter()
        match(ego, cav, init, params)
        if report is not None:
            report(params, time.perf_counter() - before)
    return time.perf_counter() - started


def _print(params: CBMParams, seconds: float) -> None:
    changed = {k: v for k, v in vars(params).items() if v != getattr(CBMParams(), k)}
    print(f"variant {changed or 'defaults'}: {seconds:.2f} s", flush=True)


def main() -> int:
    print(f"total {warm_up(report=_print):.2f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
