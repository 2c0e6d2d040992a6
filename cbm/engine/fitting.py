"""The robust fit's kernels (``cbm.estimate``, eq. 15 of the paper): weighted Procrustes, Welsch
reweighting and the least-median start, compiled; each sums pair by pair in a fixed order, so the
same transform comes out compiled or not."""
from __future__ import annotations

import math

import numba
import numpy as np

RAYLEIGH_MEDIAN = math.sqrt(2.0 * math.log(2.0))
"""Median of ||e|| for e ~ N(0, I_2): the Rayleigh distribution's median in units of sigma, so a
median residual over it is a median-absolute-deviation estimate of sigma for 2-D residuals."""
WELSCH_EFFICIENT_SCALE = 2.9846 / math.sqrt(2.0)
"""nu / sigma at which Welsch's estimator is 95 % as efficient as least squares on Gaussian noise:
Holland and Welsch (1977) give the tuning constant c = 2.9846 sigma for rho(r) ~ 1 - exp(-(r/c)^2),
and our weight exp(-r^2 / (2 nu^2)) has c = sqrt(2) nu."""
INLIER_GATE = 3.0
"""Pairs within this many sigma_0 of the least-median fit are inliers (for 2-D Gaussian noise a
true pair falls outside with probability exp(-4.5) = 1.1 %)."""
MIN_TO_REJECT = 4
"""Fewest pairs among which a wrong one can be singled out: with three, any two fit exactly and
the third cannot be told from noise, so every pair counts."""
ROUNDING = 1e-10
"""Residuals within this many times the largest coordinate of the inlier gate are gated as numpy
computes them (``gated_inliers``): the two differ by less than 1e-13 times it."""
REWEIGHT_STEPS = 20
REWEIGHT_TOL = 1e-6
"""Most reweighting steps at the final scale, and the step (largest change of an entry of the
transform) below which they stop."""


@numba.njit(cache=True, nogil=True)
def procrustes(src, dst, w):
    """``weighted_procrustes`` of float (K, 2) ``src``, ``dst`` and (K,) weights ``w`` (two positive),
    summed pair by pair in order: the same transform compiled or not."""
    total = 0.0
    for k in range(len(w)):
        total += w[k]
    ms0, ms1, md0, md1 = 0.0, 0.0, 0.0, 0.0
    for k in range(len(w)):
        wk = w[k] / total
        ms0, ms1 = ms0 + wk * src[k, 0], ms1 + wk * src[k, 1]
        md0, md1 = md0 + wk * dst[k, 0], md1 + wk * dst[k, 1]
    cos_part, sin_part = 0.0, 0.0
    for k in range(len(w)):
        wk = w[k] / total
        a0, a1, b0, b1 = src[k, 0] - ms0, src[k, 1] - ms1, dst[k, 0] - md0, dst[k, 1] - md1
        cos_part += wk * (a0 * b0 + a1 * b1)
        sin_part += wk * (a0 * b1 - a1 * b0)
    theta = math.atan2(sin_part, cos_part)
    c, s = math.cos(theta), math.sin(theta)
    T = np.zeros((3, 3))
    T[0, 0], T[0, 1], T[0, 2] = c, -s, md0 - (c * ms0 - s * ms1)
    T[1, 0], T[1, 1], T[1, 2] = s, c, md1 - (s * ms0 + c * ms1)
    T[2, 2] = 1.0
    return T


@numba.njit(cache=True, nogil=True)
def residuals_into(T, src, dst, r):
    """``r[k] = ||T(src_k) - dst_k||`` (``residuals``) in a kernel."""
    for k in range(len(src)):
        dx = T[0, 0] * src[k, 0] + T[0, 1] * src[k, 1] + T[0, 2] - dst[k, 0]
        dy = T[1, 0] * src[k, 0] + T[1, 1] * src[k, 1] + T[1, 2] - dst[k, 1]
        r[k] = math.sqrt(dx * dx + dy * dy)


@numba.njit(cache=True, nogil=True)
def inlier_sigma(r, inlier):
    """Per-axis std-dev of the inliers' residuals with the fit's 3 degrees of freedom taken out:
    ``sqrt(sum r^2 / (2 K_in - 3))`` (0 below 2 inliers)."""
    k, total = 0, 0.0
    for n in range(len(r)):
        if inlier[n]:
            k += 1
            total += r[n] ** 2
    return math.sqrt(total / (2 * k - 3)) if k >= 2 else 0.0


@numba.njit(cache=True, nogil=True)
def _reweighted(src, dst, T, nu, max_inner, tol):
    """Iteratively reweighted weighted Procrustes at a fixed Welsch scale ``nu`` (Welsch weights
    ``exp(-r^2 / (2 nu^2))``), from ``T``: at most ``max_inner`` steps, until a step moves no entry
    of ``T`` by ``tol`` or fewer than two weights are above 1e-12. Returns ``T`` and its weights."""
    r, w = np.empty(len(src)), np.empty(len(src))
    residuals_into(T, src, dst, r)
    for _ in range(max_inner):
        if _welsch_into(r, nu, w) < 2:
            break
        T_next = procrustes(src, dst, w)
        step = np.abs(T_next - T).max()
        T = T_next
        residuals_into(T, src, dst, r)
        if step < tol:
            break
    _welsch_into(r, nu, w)
    return T, w


@numba.njit(cache=True, nogil=True)
def _welsch_into(r, nu, w):
    """Welsch weights ``w = exp(-r^2 / (2 nu^2))``; returns how many are above 1e-12."""
    positive = 0
    for k in range(len(r)):
        w[k] = math.exp(-(r[k] ** 2) / (2.0 * nu ** 2))
        positive += w[k] > 1e-12
    return positive


@numba.njit(cache=True, nogil=True)
def _inlier_fit(src, dst, inlier, bounds, floor):
    """Step 2 of ``robust_fit``: (T, sigma) of the least-squares fit of the ``inlier`` pairs after a
    pair left out comes back within ``bounds[K_in]`` sigma of it (``readmit_bounds``), the fit
    then repeated. Zero weights leave ``procrustes``'s sums as they are, so fitting every pair at
    weight 1 or 0 is fitting the inliers alone."""
    weight = inlier.astype(np.float64)
    T = procrustes(src, dst, weight)
    r = np.empty(len(src))
    residuals_into(T, src, dst, r)
    kept = int(weight.sum())
    if kept < len(src):
        limit = bounds[kept] * max(inlier_sigma(r, inlier), floor)
        back = r <= limit
        if (back != inlier).any():
            if np.count_nonzero(back) < 2:
                raise ValueError("weights must hold at least two positive entries")
            inlier = back
            T = procrustes(src, dst, inlier.astype(np.float64))
            residuals_into(T, src, dst, r)
    return T, max(inlier_sigma(r, inlier), floor)


@numba.njit(cache=True, nogil=True)
def _two_point_fit(src, dst, a, b):
    """(cos, sin, tx, ty) of the least-squares rigid fit of the two pairs a and b: the angle turns
    ``src_b - src_a`` onto ``dst_b - dst_a`` and the midpoints coincide."""
    ds0, ds1, dd0, dd1 = src[b, 0] - src[a, 0], src[b, 1] - src[a, 1], dst[b, 0] - dst[a, 0], dst[b, 1] - dst[a, 1]
    theta = math.atan2(ds0 * dd1 - ds1 * dd0, ds0 * dd0 + ds1 * dd1)
    c, s = math.cos(theta), math.sin(theta)
    ms0, ms1 = 0.5 * (src[a, 0] + src[b, 0]), 0.5 * (src[a, 1] + src[b, 1])
    md0, md1 = 0.5 * (dst[a, 0] + dst[b, 0]), 0.5 * (dst[a, 1] + dst[b, 1])
    return c, s, md0 - (c * ms0 - s * ms1), md1 - (s * ms0 + c * ms1)


@numba.njit(cache=True, nogil=True)
def _least_median(src, dst, a, b, h):
    """(cos, sin, tx, ty, m) of the first two-pair fit (``_two_point_fit`` of each ``a[f], b[f]``)
    whose ``h``-th smallest squared residual m is smallest, as ``argmin`` over every fit's would
    give. A fit's ``h``-th smallest is only selected when more than ``h`` of its squares lie below
    the smallest so far; otherwise it is at least that one and cannot come first, and its squares
    stop as soon as too few are left to get there."""
    squares = np.empty(len(src))
    best, smallest = _two_point_fit(src, dst, a[0], b[0]), np.inf
    for f in range(len(a)):
        c, s, tx, ty = _two_point_fit(src, dst, a[f], b[f])
        below = 0
        for k in range(len(src)):
            dx = c * src[k, 0] - s * src[k, 1] + tx - dst[k, 0]
            dy = s * src[k, 0] + c * src[k, 1] + ty - dst[k, 1]
            squares[k] = dx * dx + dy * dy
            below += squares[k] < smallest
            if below + len(src) - 1 - k <= h:
                break
        if below > h:
            best, smallest = (c, s, tx, ty), _select(squares, h)
    return best[0], best[1], best[2], best[3], smallest


@numba.njit(cache=True, nogil=True)
def _select(values, h):
    """The ``h``-th smallest of ``values`` (Hoare's quickselect, reordering them in place)."""
    lo, hi = 0, len(values) - 1
    while lo < hi:
        pivot = values[(lo + hi) // 2]
        i, j = lo, hi
        while i <= j:
            while values[i] < pivot:
                i += 1
            while values[j] > pivot:
                j -= 1
            if i <= j:
                values[i], values[j] = values[j], values[i]
                i += 1
                j -= 1
        if h <= j:
            hi = j
        elif h >= i:
            lo = i
        else:
            break
    return values[h]


@numba.njit(cache=True, nogil=True)
def _ordered_least_median(src, dst, a, b):
    """``_least_median`` of the pairs in ``by_centroid_distance`` order, at index ``K // 2`` counted from 0."""
    order = by_centroid_distance(src, dst)
    return _least_median(src[order], dst[order], a, b, len(src) // 2)


@numba.njit(cache=True, nogil=True)
def by_centroid_distance(src, dst):
    """The pairs' order by their ``dst`` point's distance from the ``dst`` centroid, then their
    ``src`` point's from the ``src`` centroid, then their index: ``np.lexsort`` of the two distances
    as numpy computes them (the centroid a sum row after row over K, each distance
    ``sqrt(dx * dx + dy * dy)``)."""
    to_src, to_dst = _centroid_distances(src), _centroid_distances(dst)
    order = np.argsort(to_src, kind="mergesort")
    return order[np.argsort(to_dst[order], kind="mergesort")]


@numba.njit(cache=True, nogil=True)
def _centroid_distances(points):
    """Each (K, 2) point's distance from their centroid (``by_centroid_distance``)."""
    mx, my = 0.0, 0.0
    for k in range(len(points)):
        mx, my = mx + points[k, 0], my + points[k, 1]
    mx, my = mx / len(points), my / len(points)
    out = np.empty(len(points))
    for k in range(len(points)):
        dx, dy = points[k, 0] - mx, points[k, 1] - my
        out[k] = math.sqrt(dx * dx + dy * dy)
    return out


@numba.njit(cache=True, nogil=True)
def least_median_sigma(median, k):
    """Rousseeuw and Leroy's (1987) scale of a least-median fit of ``k`` pairs, for 2-D residuals:
    the Rayleigh median ``median / sqrt(2 ln 2)`` times their small-sample factor ``1 + 5 / (n - p)``
    (``n = 2k`` coordinates, ``p = 3`` parameters), which undoes the fit's choice of the smallest median."""
    return median / RAYLEIGH_MEDIAN * (1.0 + 5.0 / max(2 * k - 3, 1))


@numba.njit(cache=True, nogil=True)
def gated_inliers(src, dst, a, b, floor):
    """Step 1 of ``robust_fit``: (inliers, T, limit, sure) of the least median of squares (Rousseeuw,
    JASA 1984) over the two-pair fits ``a, b`` (``hypothesis_pairs``) of the pairs in
    ``by_centroid_distance`` order, so that the answer depends neither on the input order nor on
    where either frame lies: the fit ``T`` whose ``h``-th smallest residual, ``h = floor(K/2) + 1``,
    is smallest (it stands while fewer than half of the pairs are wrong), and the pairs within
    ``limit`` = ``INLIER_GATE`` sigma_0 (``least_median_sigma``) of it. Every pair is an inlier
    below ``MIN_TO_REJECT`` pairs. ``sure`` is False when a residual lies within rounding
    (``ROUNDING`` times the largest coordinate) of ``limit``: numpy's ``residuals``, which the gate
    reads, round the products otherwise (BLAS), so the caller then gates those."""
    n = len(src)
    if n < MIN_TO_REJECT:
        return np.ones(n, np.bool_), np.eye(3), np.inf, True
    c, s, tx, ty, median = _ordered_least_median(src, dst, a, b)
    T = np.array([[c, -s, tx], [s, c, ty], [0.0, 0.0, 1.0]])
    limit = INLIER_GATE * max(least_median_sigma(math.sqrt(median), n), floor)
    r = np.empty(n)
    residuals_into(T, src, dst, r)
    margin = ROUNDING * max(np.abs(src).max(), np.abs(dst).max(), abs(tx), abs(ty))
    return r <= limit, T, limit, not (np.abs(r - limit) <= margin).any()


@numba.njit(cache=True, nogil=True)
def welsch_fit(src, dst, inlier, bounds, floor):
    """Steps 2-3 of ``robust_fit`` from its ``inlier`` pairs (every pair when fewer than two are):
    (T, weights, sigma) of ``_inlier_fit`` followed by ``_reweighted`` at nu = c sigma."""
    if np.count_nonzero(inlier) < 2:
        inlier = np.ones(len(inlier), np.bool_)
    T, sigma = _inlier_fit(src, dst, inlier, bounds, floor)
    T, weights = _reweighted(src, dst, T, WELSCH_EFFICIENT_SCALE * sigma, REWEIGHT_STEPS, REWEIGHT_TOL)
    return T, weights, sigma

