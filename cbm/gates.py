"""Noise-aware gates (beyond the paper, step 7c): how far apart two detections of one
object may lie, read from the scene itself rather than fixed.

The scale is the pairs' own: the residuals' per-axis std-dev (``scene_sigma``), read from pairs the
robust fit (eq. 15) and the gate have already cleaned, never below the least detection noise
assumed; the heading noise likewise (``heading_sigma``). A pair is then weighed against
coincidence: a CAV box lies within distance d of an ego box by chance with probability about
``lambda * pi d^2`` (``lambda`` the boxes' density, ``clutter_density``) and its heading axis at a
uniform angle, while one object seen twice lies there with the 2-D Gaussian density of the
residuals and a half-normal heading angle. A pair is kept while the sum of the two log-likelihood
ratios (``pair_log_ratio``, ``heading_log_ratio``) is positive, inside ``CBMParams.refine_gate``
sigma: in a crowded or noisy scene the gate narrows (wrong pairs 2-3 m off are dropped unless
their headings agree), in a sparse or clean one it stays at 3 sigma.
"""
from __future__ import annotations

import math

import numpy as np

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


HEADING_FLOOR = math.radians(5.0)
"""Radians. The least std-dev assumed of the angle between two detections' heading axes."""


def heading_sigma(axis_difference: np.ndarray, floor: float = HEADING_FLOOR) -> float:
    """Std-dev of the angle between the heading axes of the pairs' two detections (radians): their
    root mean square, at least ``floor``."""
    if len(axis_difference) == 0:
        return floor
    return max(math.sqrt(float(np.mean(np.asarray(axis_difference) ** 2))), floor)


def heading_log_ratio(axis_difference: np.ndarray, sigma: float) -> np.ndarray:
    """Log-likelihood ratio of the angles between heading axes (in [0, pi/2]): a half-normal of
    std-dev ``sigma`` (one object seen twice) against the uniform angle of two unrelated boxes:
    ``log(2 / (sqrt(2 pi) sigma)) - a^2 / (2 sigma^2) - log(2 / pi)``."""
    a = np.asarray(axis_difference)
    return math.log(2.0 / (math.sqrt(2.0 * math.pi) * sigma)) - a ** 2 / (2.0 * sigma ** 2) - math.log(2.0 / math.pi)
