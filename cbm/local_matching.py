"""Context similarity-based coarse matching (paper eq. 7-8 and Algorithm 1).

For an anchor pair (i, j) a candidate (i', j') is accepted when the context vectors
``z = z_ii'`` and ``w = z_jj'`` satisfy

    arccos(|z . w| / (|z| |w|)) <= sigma1      and      ||z - w||_1 <= sigma2        (eq. 7)

Testing all (Ne Nc)^2 quadruples is what makes the released code dense. Here the CAV context
vectors are bucketed in a uniform grid whose cells are at least the L1 radius wide, so each ego
context vector only meets the CAV vectors of its 3 x 3 neighbouring cells: the work grows with
the number of accepted quadruples, not with (Ne Nc)^2. Pair ids are ``i * Nc + j`` throughout.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from .context import Context

MAX_GRID_CELLS_PER_AXIS = 2048


@dataclass(frozen=True)
class Quadruples:
    """Accepted (anchor pair, candidate pair) quadruples, one row each."""

    anchor: np.ndarray
    """(Q,) pair id of the anchor (i, j)."""
    member: np.ndarray
    """(Q,) pair id of the candidate (i', j')."""
    l1: np.ndarray
    """(Q,) L1 distance of the two context vectors."""


@dataclass(frozen=True)
class VectorGrid:
    """CAV context vectors bucketed by cell and, inside a cell, sorted by their anchor's heading:
    the vectors of cell c are ``order[start[c]:start[c + 1]]``."""

    origin: np.ndarray
    cell: float
    shape: tuple[int, int]
    start: np.ndarray
    order: np.ndarray


def build_grid(vectors: np.ndarray, anchor_heading: np.ndarray, radius: float) -> VectorGrid:
    """Bucket vectors in square cells no narrower than ``radius``, at most 2048 cells per axis."""
    if len(vectors) == 0:
        return VectorGrid(np.zeros(2), 1.0, (1, 1), np.zeros(2, dtype=np.int64), np.zeros(0, dtype=np.int64))
    origin = vectors.min(axis=0)
    extent = float((vectors.max(axis=0) - origin).max())
    cell = max(radius, extent / (MAX_GRID_CELLS_PER_AXIS - 1), 1e-9)
    ij = np.floor((vectors - origin) / cell).astype(np.int64)
    shape = (int(ij[:, 0].max()) + 1, int(ij[:, 1].max()) + 1)
    cell_id = ij[:, 0] * shape[1] + ij[:, 1]
    order = np.lexsort((anchor_heading, cell_id)).astype(np.int64)
    start = np.concatenate([[0], np.cumsum(np.bincount(cell_id, minlength=shape[0] * shape[1]))]).astype(np.int64)
    return VectorGrid(origin, cell, shape, start, order)


@numba.njit(cache=True)
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


@numba.njit(cache=True)
def _same_sign_range(cav_heading, lo, hi, ego_heading, sign):
    """Rows of one cell (sorted by heading) that may have ``sign`` against an ego anchor with
    ``ego_heading``: +1 where the folded headings differ by at most pi/2. A hair wider than exact;
    the caller checks every row."""
    margin = 1e-9
    if ego_heading >= 0.0:
        cut = ego_heading - 0.5 * math.pi
        if sign > 0:
            return lo + np.searchsorted(cav_heading[lo:hi], cut - margin), hi
        return lo, lo + np.searchsorted(cav_heading[lo:hi], cut + margin, side="right")
    cut = ego_heading + 0.5 * math.pi
    if sign > 0:
        return lo, lo + np.searchsorted(cav_heading[lo:hi], cut + margin, side="right")
    return lo + np.searchsorted(cav_heading[lo:hi], cut - margin), hi


@numba.njit(cache=True)
def _join(ego_anchor, ego_member, ego_vectors, ego_heading, cav_anchor, cav_member, cav_vectors, cav_heading,
          signs, both_signs, n_cav, origin, cell, nx, ny, start, cos2_sigma1, radius, out_anchor, out_member, out_l1):
    """Accepted quadruples into the ``out_`` arrays; returns how many there are, which may exceed the
    arrays' length (then only the first ones were written). The CAV arrays are in grid order, cell c
    holding rows start[c]:start[c + 1]."""
    capacity = len(out_anchor)
    n = 0
    for u in range(len(ego_vectors)):
        a = ego_anchor[u]
        sign_row = signs[a]
        zx, zy = ego_vectors[u, 0], ego_vectors[u, 1]
        for flip in range(2 if both_signs else 1):
            sign = 1.0 - 2.0 * flip
            cx = int(math.floor((sign * zx - origin[0]) / cell))
            cy = int(math.floor((sign * zy - origin[1]) / cell))
            for ix in range(max(cx - 1, 0), min(cx + 2, nx)):
                for iy in range(max(cy - 1, 0), min(cy + 2, ny)):
                    c = ix * ny + iy
                    lo, hi = start[c], start[c + 1]
                    if both_signs and hi > lo:
                        lo, hi = _same_sign_range(cav_heading, lo, hi, ego_heading[a], sign)
                    for v in range(lo, hi):
                        b = cav_anchor[v]
                        if sign_row[b] != sign:
                            continue
                        l1 = _accepts(zx, zy, sign * cav_vectors[v, 0], sign * cav_vectors[v, 1], cos2_sigma1, radius)
                        if l1 < 0.0:
                            continue
                        if n < capacity:
                            out_anchor[n] = a * n_cav + b
                            out_member[n] = ego_member[u] * n_cav + cav_member[v]
                            out_l1[n] = l1
                        n += 1
    return n


def accepted_quadruples(ego: Context, cav: Context, ego_heading: np.ndarray, cav_heading: np.ndarray,
                        signs: np.ndarray, sigma1_rad: float, radius: float) -> Quadruples:
    """Every quadruple (i, j, i', j') with angle <= sigma1 and L1 <= ``radius`` (eq. 7).

    ``signs[i, j]`` (+1 or -1) turns the CAV context of j by pi when compared with ego object i
    (see ``cbm.context.pair_signs``); the headings are the folded ones the contexts were built with.
    """
    n_cav = len(cav_heading)
    grid = build_grid(cav.vectors, cav_heading[cav.anchor], radius)
    o = grid.order
    arguments = (ego.anchor, ego.member, ego.vectors, np.ascontiguousarray(ego_heading, dtype=float),
                 cav.anchor[o], cav.member[o], np.ascontiguousarray(cav.vectors[o]),
                 np.ascontiguousarray(cav_heading[cav.anchor[o]], dtype=float),
                 np.ascontiguousarray(signs, dtype=np.float64), bool(np.any(signs < 0)), n_cav,
                 grid.origin, grid.cell, grid.shape[0], grid.shape[1], grid.start, math.cos(sigma1_rad) ** 2, radius)
    capacity = len(ego.vectors) * max(8, n_cav // 10) + 1024
    while True:
        out = np.empty(capacity, np.int64), np.empty(capacity, np.int64), np.empty(capacity, np.float64)
        n = _join(*arguments, *out)
        if n <= capacity:
            return Quadruples(anchor=out[0][:n], member=out[1][:n], l1=out[2][:n])
        capacity = n
