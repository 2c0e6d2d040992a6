"""Noise-aware gates (beyond the paper; DESIGN.md step 7c): how far apart two detections of one
object may lie, read from the scene itself rather than fixed.

The scale is the pairs' own: the residuals' per-axis std-dev (``scene_sigma``), read from pairs the
robust fit (eq. 14) and the gate have already cleaned, never below the least detection noise
assumed. The gate then weighs a pair against coincidence: a CAV box lands within distance d of an ego box by chance with
probability about ``lambda * pi d^2`` (``lambda`` the boxes' density, ``clutter_density``), while a
true pair lies there with the 2-D Gaussian density of the residuals. A pair is kept while its
log-likelihood ratio (``pair_log_ratio``) is positive: in a crowded or noisy scene the gate narrows
(wrong pairs 2-3 m off are dropped), in a sparse or clean one it widens to ``CBMParams.refine_gate``
sigma.
"""
from __future__ import annotations

import math

import numpy as np

MIN_GATE = 2.0
"""Sigmas. The narrowest gate: a true pair falls outside 2 sigma with probability exp(-2) = 13.5 %."""
SMALLEST_AREA = 100.0
"""Square metres. The least area the boxes are spread over (a handful of boxes in a line has none)."""


def scene_sigma(r: np.ndarray, floor: float) -> float:
    """Per-axis std-dev of the 2-D residuals ``r`` (metres) of a rigid fit of the same pairs, with
    the fit's 3 degrees of freedom taken out: ``sqrt(sum r^2 / (2K - 3))``; at least ``floor``.
    (A median-absolute-deviation estimate, ``median(r) / sqrt(2 ln 2)``, read the scale lower on
    the gated pairs of light-noise scenes and lost 1 % of their true pairs: docs/results.md.)"""
    k = len(r)
    if k < 2:
        return floor
    return max(math.sqrt(float(np.sum(np.asarray(r) ** 2)) / (2 * k - 3)), floor)


def clutter_density(xy: np.ndarray) -> float:
    """Boxes per square metre over the bounding rectangle of the centres ``xy`` (at least
    ``SMALLEST_AREA``): how likely a box lies near a point by chance."""
    if len(xy) == 0:
        return 1.0 / SMALLEST_AREA
    extent = xy.max(axis=0) - xy.min(axis=0)
    return len(xy) / max(float(extent[0] * extent[1]), SMALLEST_AREA)


def pair_log_ratio(d: np.ndarray, sigma: float, density: float) -> np.ndarray:
    """Log-likelihood ratio of pairs at distances ``d``: one object seen twice (a 2-D Gaussian of
    per-axis std-dev ``sigma``) against a box there by chance (density ``density``):
    ``-log(2 pi sigma^2) - d^2 / (2 sigma^2) - log(density)``."""
    return -math.log(2.0 * math.pi * sigma ** 2 * density) - np.asarray(d) ** 2 / (2.0 * sigma ** 2)


def gate_width(sigma: float, density: float, widest: float) -> float:
    """Sigmas. Where ``pair_log_ratio`` turns negative, ``sqrt(-2 log(2 pi sigma^2 density))``,
    clipped to [``MIN_GATE``, ``widest``] (``widest`` below ``MIN_GATE`` wins)."""
    log_ratio = -math.log(2.0 * math.pi * sigma ** 2 * density)
    return min(max(math.sqrt(2.0 * max(log_ratio, 0.0)), MIN_GATE), widest)
