"""Transform estimation from matched centres (paper eq. 15-16).

The robust loss psi of eq. 15 is Welsch's, ``1 - exp(-r^2 / (2 nu^2))``, minimised as in "Fast and
Robust Iterative Closest Point" (Zhang, Yao, Deng, TPAMI 2022) with the correspondences fixed:
iteratively reweighted weighted Procrustes, started from a least-median fit and run at a scale nu
that follows the noise the residuals show (``robust_fit``).
"""
from __future__ import annotations

import functools
import math

import numpy as np
from scipy.special import fdtri

from . import se2
from .engine.fitting import WELSCH_EFFICIENT_SCALE, gated_inliers, inlier_sigma, procrustes, welsch_fit
from .result import Fit

GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0
LMEDS_HYPOTHESES = 256
"""Most two-pair hypotheses the least-median start tries."""
READMIT_ALPHA = 1e-3
"""A pair left out comes back unless a true pair would lie as far out with at most this probability."""
READMIT_CAP = 10.0
"""A pair more than this many sigma off stays out, however few the inliers that read sigma."""


def weighted_procrustes(src: np.ndarray, dst: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """The rigid transform ``T`` minimising ``sum_k w_k ||dst_k - T src_k||^2``.

    Kabsch (1976) / Umeyama (1991) in closed form for SE(2): with weighted centroids
    ``mu_s, mu_d`` and centred points ``a_k = src_k - mu_s``, ``b_k = dst_k - mu_d``, the angle is
    ``theta = atan2(sum w (a x b), sum w (a . b))`` (the SVD solution with det R = +1) and
    ``t = mu_d - R(theta) mu_s`` (``procrustes``). Needs at least two points of positive weight.
    """
    src = np.ascontiguousarray(src, dtype=float).reshape(-1, 2)
    dst = np.ascontiguousarray(dst, dtype=float).reshape(-1, 2)
    w = np.ones(len(src)) if weights is None else np.ascontiguousarray(weights, dtype=float)
    if np.count_nonzero(w > 0) < 2:
        raise ValueError("weights must hold at least two positive entries")
    return procrustes(src, dst, w)


def residuals(T: np.ndarray, src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """||T(src_k) - dst_k|| for every pair."""
    return np.linalg.norm(se2.apply_points(T, src) - dst, axis=1)


def least_squares_fit(src: np.ndarray, dst: np.ndarray, nu_floor: float) -> Fit:
    """Plain least squares (every weight 1), as the authors' released code fits (SVD)."""
    T = weighted_procrustes(src, dst)
    r = residuals(T, src, dst)
    sigma = max(inlier_sigma(r, np.ones(len(r), dtype=bool)), nu_floor / WELSCH_EFFICIENT_SCALE)
    return Fit(T, np.ones(len(src)), math.inf, sigma)


@functools.lru_cache(maxsize=256)
def hypothesis_pairs(k: int, limit: int = LMEDS_HYPOTHESES) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs (a, b), a != b, of the two-pair hypotheses: all of them when there are at most
    ``limit``, else ``limit`` of them spread evenly: round after round every pair is an ``a``,
    its ``b`` a fixed offset ahead, the offsets spread by the golden ratio. Read-only, kept per size."""
    if k * (k - 1) // 2 <= limit:
        a, b = np.triu_indices(k, 1)
    else:
        h = np.arange(limit)
        a, rounds = h % k, h // k + 1
        offset = 1 + np.floor(rounds * GOLDEN * (k - 1)).astype(np.intp) % (k - 1)
        b = (a + offset) % k
    a.flags.writeable, b.flags.writeable = False, False
    return a, b


@functools.lru_cache(maxsize=256)
def readmit_bounds(most: int) -> np.ndarray:
    """For K = 0..``most`` inliers: how many sigma (read from K pairs) a true pair's residual stays
    below with probability 1 - ``READMIT_ALPHA``: ``sqrt(2 F(2, 2K - 3))`` at that level (the noise
    estimate of few pairs is itself uncertain), at most ``READMIT_CAP``. Read-only, kept per size."""
    dfd = np.maximum(2 * np.arange(most + 1) - 3, 1)
    bounds = np.minimum(np.sqrt(2.0 * fdtri(2, dfd, 1.0 - READMIT_ALPHA)), READMIT_CAP)
    bounds.flags.writeable = False
    return bounds


def robust_fit(src: np.ndarray, dst: np.ndarray, nu_floor: float) -> Fit:
    """Robust SE(2) fit of eq. 15 with Welsch weights and a scale that follows the data (>= 2 pairs).

    1. Single out wrong pairs where fewer than half of them can pull (from ``MIN_TO_REJECT``
       pairs on): the least-median fit and its scale sigma_0 (``gated_inliers``,
       ``least_median_sigma``); pairs within ``INLIER_GATE`` sigma_0 of it are the inliers.
    2. Read the noise from the inliers: their least-squares fit and its residual std-dev sigma
       (``inlier_sigma``, never below ``nu_floor / c``) -- Rousseeuw and Leroy's reweighted least
       squares (1987, ch. 5); a pair left out comes back when it lies within ``readmit_bounds``
       sigma of that fit (few inliers know their noise only roughly), then the fit is repeated.
    3. Minimise eq. 15 by iteratively reweighted Procrustes (the majorise-minimise step of Zhang,
       Yao, Deng, TPAMI 2022) at nu = c sigma, ``c = WELSCH_EFFICIENT_SCALE``: Holland and Welsch's
       95 %-efficiency constant.

    So on Gaussian inliers the fit stays close to least squares however large the detection noise
    (a scale annealed to a fixed floor left it on the two or three pairs that agree best), and pairs
    many sigma off weigh nothing. The scale is read once, from a least-squares fit of the inliers:
    read from the robust fit's own residuals it would shrink on few pairs, round after round.
    """
    src, dst = np.ascontiguousarray(src, dtype=float), np.ascontiguousarray(dst, dtype=float)
    floor = nu_floor / WELSCH_EFFICIENT_SCALE
    inlier, T, limit, sure = gated_inliers(src, dst, *hypothesis_pairs(len(src)), floor)
    if not sure:
        inlier = residuals(T, src, dst) <= limit
    T, weights, sigma = welsch_fit(src, dst, inlier, readmit_bounds(len(src)), floor)
    return Fit(T, weights, WELSCH_EFFICIENT_SCALE * sigma, sigma)
