"""Context similarity-based coarse matching (paper eq. 7-8 and Algorithm 1).

For an anchor pair (i, j) a candidate (i', j') is accepted when the context vectors
``z = z_ii'`` and ``w = z_jj'`` satisfy

    arccos(|z . w| / (|z| |w|)) <= sigma1      and      ||z - w||_1 <= sigma2        (eq. 7)

Testing all (Ne Nc)^2 quadruples is what makes the released code dense. Here the join is
output-sensitive and never holds the accepted quadruples of eq. 8:

- the CAV context vectors lie in a grid of cells half sigma2 wide (``VectorGrid``); an ego vector z
  meets only the vectors of the cells that the L1 diamond around it touches, column by column;
- that join counts card(L_ij) for every anchor and lists only the quadruples within sigma3, the
  voting sets of the consensus (``count_candidates``); it runs in parallel over ranges of ego objects,
  each owning its anchors' counters, and its lists are joined in ego order, so nothing depends on
  the threads;
- the members of one L_ij are listed again when the selection asks for them
  (``CandidateSets.members``): against the CAV anchor's vectors sorted by x, O(N log N).

Pair ids are ``i * Nc + j`` throughout.
"""
from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numba
import numpy as np

from .context import Context

CELLS_PER_RADIUS = 2
"""Grid cells per L1 radius: smaller cells cut the vectors a query scans, at more cells to visit."""
MAX_CELLS = 1 << 22
"""Most grid cells (32 MB of row offsets); a wider scene gets wider cells."""
MARGIN = 1e-6
"""Metres added to every search window, so that rounding never hides a vector eq. 7 accepts;
each vector in the window is then tested exactly."""
PARALLEL_FROM = 2_000
"""Context vectors per agent from which the joins are split over threads."""
THREADS = 2
_POOL = ThreadPoolExecutor(max_workers=THREADS, thread_name_prefix="cbm-join")


@dataclass(frozen=True)
class VectorGrid:
    """CAV context vectors bucketed in square cells of side ``cell``, column by column: cell
    (kx, ky) holds rows ``start[kx * ny + ky]:start[kx * ny + ky + 1]``, so the cells ky0..ky1 of
    one column are one run of rows."""

    x0: float
    y0: float
    cell: float
    nx: int
    ny: int
    start: np.ndarray
    x: np.ndarray
    y: np.ndarray
    anchor: np.ndarray
    member: np.ndarray


def build_grid(cav: Context, radius: float) -> VectorGrid:
    """A grid of cells ``radius / CELLS_PER_RADIUS`` wide (wider when it would pass ``MAX_CELLS``)."""
    x, y = cav.vectors[:, 0], cav.vectors[:, 1]
    if len(x) == 0:
        return VectorGrid(0.0, 0.0, 1.0, 1, 1, np.zeros(2, np.int64), x, y, cav.anchor, cav.member)
    x0, y0 = float(x.min()), float(y.min())
    width, height = float(x.max()) - x0, float(y.max()) - y0
    cell = max(radius / CELLS_PER_RADIUS, math.sqrt((width + 1.0) * (height + 1.0) / MAX_CELLS), 1e-9)
    nx, ny = int(width // cell) + 1, int(height // cell) + 1
    start = np.zeros(nx * ny + 1, np.int64)
    gx, gy, anchor, member = np.empty(len(x)), np.empty(len(x)), np.empty(len(x), np.int64), np.empty(len(x), np.int64)
    _bucket(cav.vectors, cav.anchor, cav.member, x0, y0, cell, nx, ny, start, gx, gy, anchor, member)
    return VectorGrid(x0, y0, cell, nx, ny, start, gx, gy, anchor, member)


@numba.njit(cache=True, nogil=True)
def _bucket(vectors, anchor, member, x0, y0, cell, nx, ny, start, gx, gy, g_anchor, g_member):
    """Counting sort of the vectors by cell (column-major), keeping their order inside a cell."""
    cell_of = np.empty(len(vectors), np.int64)
    for v in range(len(vectors)):
        kx = min(int(math.floor((vectors[v, 0] - x0) / cell)), nx - 1)
        ky = min(int(math.floor((vectors[v, 1] - y0) / cell)), ny - 1)
        cell_of[v] = kx * ny + ky
        start[cell_of[v] + 1] += 1
    for c in range(nx * ny):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    for v in range(len(vectors)):
        row = fill[cell_of[v]]
        gx[row], gy[row], g_anchor[row], g_member[row] = vectors[v, 0], vectors[v, 1], anchor[v], member[v]
        fill[cell_of[v]] += 1


@numba.njit(cache=True, nogil=True, inline="always")
def _accepts(zx, zy, wx, wy, cos2_sigma1, radius):
    """L1 distance of z and w when eq. 7 accepts them, else -1.

    The angle test arccos(|z.w| / (|z| |w|)) <= sigma1 is evaluated as
    (z.w)^2 >= cos^2(sigma1) |z|^2 |w|^2 (sigma1 <= 90 degrees), without square roots.
    """
    l1 = abs(zx - wx) + abs(zy - wy)
    if l1 > radius:
        return -1.0
    squared_norms = (zx * zx + zy * zy) * (wx * wx + wy * wy)
    dot = zx * wx + zy * wy
    if squared_norms <= 0.0 or dot * dot < cos2_sigma1 * squared_norms:
        return -1.0
    return l1


@numba.njit(cache=True, nogil=True, inline="always")
def _first_at_least(values, lo, hi, value):
    """The first row in lo..hi-1 of sorted ``values`` with values[row] >= value (hi when none)."""
    while lo < hi:
        mid = (lo + hi) >> 1
        if values[mid] < value:
            lo = mid + 1
        else:
            hi = mid
    return lo


@numba.njit(cache=True, nogil=True)
def _join(first, last, ego_vectors, ego_member, per_anchor, signs, both_signs, x0, y0, cell, nx, ny, start, gx, gy,
          g_anchor, g_member, cos2_sigma1, radius, sigma2, sigma3, count2, list_votes):
    """Eq. 7 for the vectors of ego objects first..last-1 against the grid of CAV vectors.

    Adds, per anchor pair a, the accepted quadruples within sigma2 to ``count2[a]``; with
    ``list_votes``, returns those within sigma3 as (anchor, member) rows, in the order found.
    The CAV frame of j is turned by ``signs[i, j]``.
    """
    n_cav = signs.shape[1]
    capacity = 1024 if list_votes else 0
    vote_anchor, vote_member, n_votes = np.empty(capacity, np.int64), np.empty(capacity, np.int64), 0
    for i in range(first, last):
        sign_row = signs[i]
        row = i * n_cav
        for u in range(i * per_anchor, (i + 1) * per_anchor):
            zx, zy = ego_vectors[u, 0], ego_vectors[u, 1]
            for flip in range(2 if both_signs else 1):
                sign = 1.0 - 2.0 * flip
                qx, qy = sign * zx, sign * zy
                k0 = max(int(math.floor((qx - radius - MARGIN - x0) / cell)), 0)
                k1 = min(int(math.floor((qx + radius + MARGIN - x0) / cell)), nx - 1)
                for k in range(k0, k1 + 1):
                    gap = max(0.0, x0 + k * cell - qx, qx - (x0 + (k + 1) * cell))
                    reach = radius - gap + MARGIN
                    if reach < 0.0:
                        continue
                    c0 = max(int(math.floor((qy - reach - y0) / cell)), 0)
                    c1 = min(int(math.floor((qy + reach - y0) / cell)), ny - 1)
                    if c1 < c0:
                        continue
                    for v in range(start[k * ny + c0], start[k * ny + c1 + 1]):
                        b = g_anchor[v]
                        if sign_row[b] != sign:
                            continue
                        l1 = _accepts(zx, zy, sign * gx[v], sign * gy[v], cos2_sigma1, radius)
                        if l1 < 0.0:
                            continue
                        if l1 <= sigma2:
                            count2[row + b] += 1
                        if list_votes and l1 <= sigma3:
                            if n_votes == capacity:
                                capacity *= 2
                                vote_anchor = _grown(vote_anchor, capacity)
                                vote_member = _grown(vote_member, capacity)
                            vote_anchor[n_votes] = row + b
                            vote_member[n_votes] = ego_member[u] * n_cav + g_member[v]
                            n_votes += 1
    return vote_anchor[:n_votes], vote_member[:n_votes]


@numba.njit(cache=True, nogil=True)
def _grown(values, capacity):
    grown = np.empty(capacity, values.dtype)
    grown[:len(values)] = values
    return grown


def _split(n_ego: int, n_vectors: int) -> list[tuple[int, int]]:
    """Ranges of ego objects for the threads (one range for small problems)."""
    if n_vectors < PARALLEL_FROM or n_ego < THREADS:
        return [(0, n_ego)]
    bounds = np.linspace(0, n_ego, 4 * THREADS + 1).astype(int)
    return list(zip(bounds[:-1], bounds[1:]))


def _run_join(ego: Context, n_ego: int, signs: np.ndarray, grid: VectorGrid, sigma1_rad: float, radius: float,
              sigma2: float, sigma3: float, count2: np.ndarray, list_votes: bool) -> tuple[np.ndarray, np.ndarray]:
    """``_join`` over all ego objects, split over threads; the voting rows in ego-object order."""
    per_anchor = max(n_ego - 1, 0)
    common = (ego.vectors, ego.member, per_anchor, signs, bool(np.any(signs < 0)), grid.x0, grid.y0, grid.cell,
              grid.nx, grid.ny, grid.start, grid.x, grid.y, grid.anchor, grid.member, math.cos(sigma1_rad) ** 2,
              radius, sigma2, sigma3, count2, list_votes)
    ranges = _split(n_ego, len(ego.vectors))
    if len(ranges) == 1:
        return _join(0, n_ego, *common)
    parts = [future.result() for future in [_POOL.submit(_join, first, last, *common) for first, last in ranges]]
    return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])


@numba.njit(cache=True, nogil=True)
def _sort_blocks(vectors, member, per_anchor, bx, by, b_member):
    """Each anchor's context vectors sorted by x, block by block."""
    for j in range(len(vectors) // max(per_anchor, 1)):
        lo = j * per_anchor
        order = np.argsort(vectors[lo:lo + per_anchor, 0], kind="mergesort")
        for k in range(per_anchor):
            bx[lo + k] = vectors[lo + order[k], 0]
            by[lo + k] = vectors[lo + order[k], 1]
            b_member[lo + k] = member[lo + order[k]]


@numba.njit(cache=True, nogil=True)
def members_into(i, j, sign, ego_vectors, ego_member, per_ego, bx, by, b_member, n_cav, cos2_sigma1, sigma2, out):
    """The members of L_ij (eq. 8) into ``out``, the anchor pair last; returns how many. The CAV
    blocks ``bx, by, b_member`` hold each anchor's vectors sorted by x (``_sort_blocks``)."""
    per_cav = n_cav - 1
    lo_j, hi_j = j * per_cav, (j + 1) * per_cav
    size = 0
    for u in range(i * per_ego, (i + 1) * per_ego):
        zx, zy = ego_vectors[u, 0], ego_vectors[u, 1]
        qx = sign * zx
        v = _first_at_least(bx, lo_j, hi_j, qx - sigma2 - MARGIN)
        while v < hi_j and bx[v] <= qx + sigma2 + MARGIN:
            if _accepts(zx, zy, sign * bx[v], sign * by[v], cos2_sigma1, sigma2) >= 0.0:
                out[size] = ego_member[u] * n_cav + b_member[v]
                size += 1
            v += 1
    if size:
        out[size] = i * n_cav + j
        size += 1
    return size


@dataclass(frozen=True)
class CandidateSets:
    """The candidate sets L_ij of every anchor (eq. 8): their sizes, and their members on demand."""

    count: np.ndarray
    """(Ne * Nc,) card(L_ij), the anchor pair included when the set is not empty."""
    lookup: tuple
    """``members_into``'s arguments after (i, j, sign) and before ``out``."""
    signs: np.ndarray
    """(Ne, Nc) how the CAV frame is turned against each ego frame (``cbm.context.pair_signs``)."""

    def sizes(self) -> np.ndarray:
        return self.count

    def members(self, anchor: int) -> np.ndarray:
        """Pair ids of L_ij for ``anchor = i * Nc + j``, the anchor pair last."""
        n_cav = self.signs.shape[1]
        i, j = divmod(int(anchor), n_cav)
        out = np.empty(int(self.count[anchor]) + 1, np.int64)
        size = members_into(i, j, float(self.signs[i, j]), *self.lookup, out)
        return out[:size]


def count_candidates(ego: Context, cav: Context, n_ego: int, n_cav: int, signs: np.ndarray, sigma1_rad: float,
                     sigma2: float, sigma3: float | None) -> tuple[CandidateSets, np.ndarray, np.ndarray]:
    """card(L_ij) at sigma2 for every anchor, and (with ``sigma3``) the (anchor, member) rows of every
    quadruple within sigma3 (the voting sets of eq. 9 without their own pairs), from one join."""
    count2 = np.zeros(n_ego * n_cav, np.int64)
    radius = sigma2 if sigma3 is None else max(sigma2, sigma3)
    vote_anchor, vote_member = _run_join(ego, n_ego, signs, build_grid(cav, radius), sigma1_rad, radius, sigma2,
                                         -1.0 if sigma3 is None else sigma3, count2, sigma3 is not None)
    count2 += count2 > 0
    bx, by, b_member = np.empty(len(cav.vectors)), np.empty(len(cav.vectors)), np.empty(len(cav.vectors), np.int64)
    _sort_blocks(cav.vectors, cav.member, max(n_cav - 1, 0), bx, by, b_member)
    lookup = (ego.vectors, ego.member, max(n_ego - 1, 0), bx, by, b_member, n_cav, math.cos(sigma1_rad) ** 2, sigma2)
    return CandidateSets(count=count2, lookup=lookup, signs=signs), vote_anchor, vote_member
