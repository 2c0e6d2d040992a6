"""card(L_ij) after a sigma2 edit by a scan instead of a join, for ``cbm.engine.cache``.

With sigma1 fixed, L_ij at sigma2 holds the quadruples eq. 8's angle test accepts whose L1
distance is within sigma2: the same numbers whatever sigma2 is. So on the first sigma2 edit of an
input the L1 distance of every accepted quadruple within a radius above it is kept with its anchor
pair (``Distances``), and card(L_ij) at any sigma2 up to that radius is counted from them
(``counted``): a pass over the kept quadruples in place of a join over the grid. A larger sigma2
keeps them anew; past ``MOST_QUADRUPLES`` nothing is kept and the join counts.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from . import tuning
from .context import Prepared
from .grid import group_signs, heading_groups, l1_and_angle, window
from .join import ANCHORS_PER_CHUNK, EgoVectors, Grids, by_column, grown, widest_column
from .threads import check_stop, parts, shared_out, stop_flag

HEADROOM = 1.5
"""The radius kept, as a factor of the sigma2 that asked for it: room for the next edits upward."""
MOST_QUADRUPLES = 8 * 2**20
"""Most quadruples kept (12 bytes each: about 100 MB)."""


@dataclass(frozen=True)
class Distances:
    """The anchor pair (``i Nc + b``) and the L1 distance of every quadruple eq. 8 accepts within
    ``radius``, for one input and sigma1; both None where they were more than ``MOST_QUADRUPLES``
    (the join counts then, at this radius and above)."""

    radius: float
    anchor: np.ndarray | None
    distance: np.ndarray | None


def distances_within(prepared: Prepared, sigma1_rad: float, radius: float, grids: Grids) -> Distances:
    """Every quadruple eq. 8 accepts within ``radius`` (with the kept ``grids``), heading group by
    heading group; from ``DISTANCES_APART_FROM`` context vectors each group in parts, all shared out
    between the threads."""
    ego = prepared.ego_context
    vectors = EgoVectors(ego.vectors, ego.member, max(len(prepared.ego_heading) - 1, 0))
    groups = heading_groups(prepared.ego_heading, prepared.signs)
    grids.for_radius(radius)
    n_parts = parts(len(ego.vectors), tuning.DISTANCES_APART_FROM)
    cos2_sigma1, stop = math.cos(sigma1_rad) ** 2, stop_flag()

    def accepted(k: int, part: np.ndarray) -> tuple:
        grid = grids.grid(k, prepared.cav_context, group_signs(prepared.signs, groups[k]))
        return _accepted(part, vectors, prepared.signs, grid, cos2_sigma1, radius, MOST_QUADRUPLES, stop)

    tasks = [lambda k=k, part=part: accepted(k, part) for k, group in enumerate(groups)
             for part in np.array_split(group, n_parts) if len(part)]
    found = shared_out(tasks) if n_parts > 1 else [task() for task in tasks]
    check_stop()
    if not all(whole for _, _, whole in found) or sum(len(anchor) for anchor, _, _ in found) > MOST_QUADRUPLES:
        return Distances(radius, None, None)
    return Distances(radius, np.concatenate([anchor for anchor, _, _ in found]),
                     np.concatenate([distance for _, distance, _ in found]))


@numba.njit(cache=True, nogil=True)
def _accepted(ego_ids, ego, signs, grid, cos2_sigma1, radius, most, stop):
    """The anchor pairs and L1 distances of the quadruples of the ego objects ``ego_ids`` that eq. 8
    accepts within ``radius`` against a grid, and True; none and False past ``most`` or once
    ``stop[0]`` is set (``threads.stop_flag``: the caller then raises ``Cancelled``). A row whose
    sign varies counts where it is the pair's, as the join counts it. Like the join, the ego vectors
    of ``ANCHORS_PER_CHUNK`` objects go column by column of the grid, and every row of a window is
    written and kept or overwritten without a branch."""
    n_cav = signs.shape[1]
    vectors, _, per_anchor = ego
    cells, start, gx, gy, g_anchor, _, g_check = grid
    ny = cells.ny
    widest = widest_column(grid)
    anchor, distance = np.empty(1024, np.int32), np.empty(1024)
    order = np.empty(ANCHORS_PER_CHUNK * per_anchor, np.int64)
    column_start = np.empty(cells.nx + 1, np.int64)
    n = 0
    for chunk in range(0, len(ego_ids), ANCHORS_PER_CHUNK):
        for q in range(by_column(ego_ids, chunk, ego, cells, column_start, order)):
            u = order[q]
            i = u // per_anchor
            zx, zy = vectors[u, 0], vectors[u, 1]
            k0, k1, c0, c1 = window(zx + zy, zx - zy, radius, cells)
            room = n + (k1 - k0 + 1) * widest
            if room > most or stop[0]:
                return anchor[:0].copy(), distance[:0].copy(), False
            while room > len(anchor):
                anchor, distance = grown(anchor, n), grown(distance, n)
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
    """card(L_ij) + 1 at ``sigma2`` (at most ``kept.radius``) of every anchor pair with a candidate,
    0 for the others (the join's counts); from ``COUNT_APART_FROM`` quadruples in parts on the
    threads, each into counters of its own, added after."""
    n_parts = parts(len(kept.anchor), tuning.COUNT_APART_FROM)
    cuts = np.linspace(0, len(kept.anchor), n_parts + 1).astype(np.int64)

    def part(a: int, b: int) -> np.ndarray:
        count2 = np.zeros(n_pairs, np.int64)
        _count_within(kept.anchor[a:b], kept.distance[a:b], sigma2, count2)
        return count2

    found = shared_out([lambda a=a, b=b: part(a, b) for a, b in zip(cuts, cuts[1:])])
    count2 = found[0]
    for other in found[1:]:
        count2 += other
    count2 += count2 > 0
    return count2
