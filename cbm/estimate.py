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
    """The SE(2) transform T minimising sum_k w_k ||T(src_k) - dst_k||^2 (closed form in 2D)."""
    w = np.ones(len(src)) if weights is None else np.asarray(weights, dtype=float)
    w = w / w.sum()
    src_mean, dst_mean = w @ src, w @ dst
    s, d = src - src_mean, dst - dst_mean
    sin_part = w @ (s[:, 0] * d[:, 1] - s[:, 1] * d[:, 0])
    cos_part = w @ (s[:, 0] * d[:, 0] + s[:, 1] * d[:, 1])
    yaw = np.arctan2(sin_part, cos_part)
    T = se2.make(0.0, 0.0, yaw)
    T[:2, 2] = dst_mean - T[:2, :2] @ src_mean
    return T


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
