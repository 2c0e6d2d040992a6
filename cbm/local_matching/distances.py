"""Step 4d of local matching: card(L_ij) after a sigma2 edit by a scan instead of a join (eq. 7-8).

With sigma1 fixed, L_ij at sigma2 holds the quadruples eq. 7's angle test accepts whose L1
distance is within sigma2: the same numbers whatever sigma2 is. Once the user edits sigma2, the
L1 distance of every accepted quadruple within a radius above it is kept with its anchor pair
(``Distances``), and card(L_ij) at any sigma2 up to that radius is counted from them
(``counted``): a pass over the kept quadruples in place of a join over the grid. A larger sigma2
keeps them anew; past ``MOST_QUADRUPLES`` nothing is kept and the join counts.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from ..context import Context
from .grid import cells, heading_groups, l1_and_angle
from .join import ANCHORS_PER_CHUNK, POOL, THREADS, _at_once, _by_column, _fresh_grids, _grids, _grown, _widest_column

HEADROOM = 1.5
"""The radius kept, as a factor of the sigma2 that asked for it: room for the next edits upward."""
MOST_QUADRUPLES = 8 * 2**20
"""Most quadruples kept (12 bytes each: about 100 MB)."""
COUNT_APART_FROM = 200_000
"""Quadruples kept from which a sigma2 edit counts them on both threads (``counted``)."""
PARALLEL_FROM = 5_000
"""Context vectors per agent from which the pass runs on both threads: it writes every quadruple
it accepts, so it pays for the handover from fewer vectors than the join (first sigma2 edit on
`synthetic:300`'s frame, 12,000 vectors: 12.5 -> 7.8 ms)."""


@dataclass(frozen=True)
class Distances:
    """The anchor pair (``i Nc + b``) and the L1 distance of eq. 7 of every quadruple eq. 7 accepts
    within ``radius``, for one input and sigma1; both None where they were more than
    ``MOST_QUADRUPLES`` (the join counts then, at this radius and above)."""

    radius: float
    anchor: np.ndarray | None
    distance: np.ndarray | None


def distances_within(ego: Context, cav: Context, ego_heading: np.ndarray, signs: np.ndarray, sigma1_rad: float,
                     radius: float, kept: dict) -> Distances | None:
    """Every quadruple eq. 7 accepts within ``radius`` (with ``kept``'s grids), heading group by
    heading group, on both threads from ``PARALLEL_FROM`` context vectors; None past
    ``MOST_QUADRUPLES``."""
    per_anchor = max(len(ego_heading) - 1, 0)
    groups = heading_groups(ego_heading, signs)
    parallel = len(ego.vectors) >= PARALLEL_FROM
    run = POOL.submit if parallel else _at_once
    _fresh_grids(kept, radius)
    grids = _grids(groups, 0, cav, signs, radius, run, kept)
    cos2_sigma1 = math.cos(sigma1_rad) ** 2
    jobs = [run(_accepted, part, ego.vectors, per_anchor, signs, grid.u0, grid.v0, grid.cell, grid.nx, grid.ny,
                grid.start, grid.x, grid.y, grid.anchor, grid.check, cos2_sigma1, radius, MOST_QUADRUPLES)
            for group, grid in zip(groups, grids) for part in (np.array_split(group, THREADS) if parallel else [group])
            if len(part)]
    parts = [job.result() for job in jobs]
    if not all(whole for _, _, whole in parts) or sum(len(anchor) for anchor, _, _ in parts) > MOST_QUADRUPLES:
        return None
    return Distances(radius, np.concatenate([anchor for anchor, _, _ in parts]),
                     np.concatenate([distance for _, distance, _ in parts]))


@numba.njit(cache=True, nogil=True)
def _accepted(ego_ids, ego_vectors, per_anchor, signs, u0, v0, cell, nx, ny, start, gx, gy, g_anchor, g_check,
              cos2_sigma1, radius, most):
    """The anchor pairs and L1 distances of the quadruples of the ego objects ``ego_ids`` that eq. 7
    accepts within ``radius`` against a grid, and True; none and False past ``most``. A row whose
    sign varies counts where it is the pair's, as the join counts it. Like the join (``_join``), the
    ego vectors of ``ANCHORS_PER_CHUNK`` objects go column by column of the grid, and every row of
    a window is written and kept or overwritten without a branch."""
    n_cav = signs.shape[1]
    widest = _widest_column(nx, ny, start)
    anchor, distance = np.empty(1024, np.int32), np.empty(1024)
    order = np.empty(ANCHORS_PER_CHUNK * per_anchor, np.int64)
    column_start = np.empty(nx + 1, np.int64)
    n = 0
    for chunk in range(0, len(ego_ids), ANCHORS_PER_CHUNK):
        for q in range(_by_column(ego_ids, chunk, per_anchor, ego_vectors, u0, cell, nx, column_start, order)):
            u = order[q]
            i = u // per_anchor
            zx, zy = ego_vectors[u, 0], ego_vectors[u, 1]
            k0, k1, c0, c1 = cells(zx + zy, zx - zy, radius, u0, v0, cell, nx, ny)
            room = n + (k1 - k0 + 1) * widest
            if room > most:
                return anchor[:0].copy(), distance[:0].copy(), False
            while room > len(anchor):
                anchor, distance = _grown(anchor, n), _grown(distance, n)
            sign_row, z2 = signs[i], zx * zx + zy * zy
            for k in range(k0, k1 + 1):
                for v in range(start[k * ny + c0], start[k * ny + c1 + 1]):
                    b, check = g_anchor[v], g_check[v]
                    l1, angle = l1_and_angle(zx, zy, z2, gx[v], gy[v], cos2_sigma1)
                    anchor[n], distance[n] = i * n_cav + b, l1
                    n += (l1 <= radius) & angle & ((check == 0) | ((check > 0) == (sign_row[b] > 0)))
    return anchor[:n].copy(), distance[:n].copy(), True


@numba.njit(cache=True, nogil=True)
def _count_within(anchor, distance, sigma2, count2):
    """Adds each quadruple within ``sigma2`` to its anchor pair's ``count2``."""
    for q in range(len(anchor)):
        count2[anchor[q]] += distance[q] <= sigma2


def counted(kept: Distances, sigma2: float, n_pairs: int) -> np.ndarray:
    """card(L_ij) at ``sigma2`` (at most ``kept.radius``) of every anchor pair, without the pair itself
    (the join's counters); from ``COUNT_APART_FROM`` quadruples the second half is counted on
    ``POOL`` into counters of its own, added after."""
    count2 = np.zeros(n_pairs, np.int64)
    half = len(kept.anchor) // 2
    if half < COUNT_APART_FROM // 2:
        _count_within(kept.anchor, kept.distance, sigma2, count2)
        return count2
    theirs = np.zeros(n_pairs, np.int64)
    job = POOL.submit(_count_within, kept.anchor[half:], kept.distance[half:], sigma2, theirs)
    _count_within(kept.anchor[:half], kept.distance[:half], sigma2, count2)
    job.result()
    count2 += theirs
    return count2
