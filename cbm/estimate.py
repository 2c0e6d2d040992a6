"""Transform estimation from matched centres (paper eq. 14-15).

The robust loss psi of eq. 14 is Welsch's, ``1 - exp(-r^2 / (2 nu^2))``, minimised as in "Fast and
Robust Iterative Closest Point" (Zhang, Yao, Deng, TPAMI 2022) with the correspondences fixed:
iteratively reweighted weighted Procrustes, nu starting at 3x the median residual of the
least-squares fit and halved down to a floor set by the expected detection noise.
"""
from __future__ import annotations

import numpy as np

from . import se2


def weighted_procrustes(src: np.ndarray, dst: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """The rigid transform ``T`` minimising ``sum_k w_k ||dst_k - T src_k||^2``.

    Kabsch (1976) / Umeyama (1991) in closed form for SE(2): with weighted centroids
    ``mu_s, mu_d`` and centred points ``a_k = src_k - mu_s``, ``b_k = dst_k - mu_d``, the angle is
    ``theta = atan2(sum w (a x b), sum w (a . b))`` (the SVD solution with det R = +1) and
    ``t = mu_d - R(theta) mu_s``. Needs at least two points of positive weight.
    """
    src = np.asarray(src, dtype=float).reshape(-1, 2)
    dst = np.asarray(dst, dtype=float).reshape(-1, 2)
    w = np.ones(len(src)) if weights is None else np.asarray(weights, dtype=float)
    if np.count_nonzero(w > 0) < 2:
        raise ValueError("weights must hold at least two positive entries")
    w = w / w.sum()
    mu_s, mu_d = w @ src, w @ dst
    a, b = src - mu_s, dst - mu_d
    cos_part = w @ (a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1])
    sin_part = w @ (a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])
    theta = float(np.arctan2(sin_part, cos_part))
    R = se2.make(0.0, 0.0, theta)[:2, :2]
    t = mu_d - R @ mu_s
    return se2.make(t[0], t[1], theta)


def residuals(T: np.ndarray, src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """||T(src_k) - dst_k|| for every pair."""
    return np.linalg.norm(se2.apply_points(T, src) - dst, axis=1)


def welsch_weights(r: np.ndarray, nu: float) -> np.ndarray:
    """Welsch weights exp(-r^2 / (2 nu^2))."""
    return np.exp(-(r ** 2) / (2.0 * nu ** 2))


def robust_se2(src: np.ndarray, dst: np.ndarray, nu_floor: float, max_inner: int = 20,
               tol: float = 1e-6) -> np.ndarray:
    """Robust SE(2) fit of eq. 14 with Welsch weights and an annealed scale nu (needs >= 2 pairs)."""
    T = weighted_procrustes(src, dst)
    r = residuals(T, src, dst)
    nu = max(3.0 * float(np.median(r)), nu_floor)
    while True:
        for _ in range(max_inner):
            w = welsch_weights(r, nu)
            if w.sum() < 1e-12 or np.count_nonzero(w > 1e-12) < 2:
                break
            T_next = weighted_procrustes(src, dst, w)
            step = np.abs(T_next - T).max()
            T, r = T_next, residuals(T_next, src, dst)
            if step < tol:
                break
        if nu <= nu_floor:
            return T
        nu = max(nu / 2.0, nu_floor)
