"""Weighted 2D Procrustes (Kabsch) fit shared by the baselines."""
from __future__ import annotations

import numpy as np

from .. import se2


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
