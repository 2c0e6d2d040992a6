"""The floor of the exact count: a bare kernel that only counts the quadruples eq. 8 accepts.

It reads the same grids the join reads (``cbm.engine.grid.build_grid``, built beforehand and not
timed), visits each ego context vector's cells in one tight loop and adds 1 per accepted quadruple
to a single counter: no per-anchor counters, no voting lists; each group's objects in as many
parts as the engine has threads, shared out as the join's work is (``cbm.engine.threads``). What the join spends
beyond it is the cost of how it counts, the measure ``bench_match.py`` prints beside it.
"""
from __future__ import annotations

import math
import time

import numba
import numpy as np

from cbm import CBMParams, se2
from cbm.engine import tuning
from cbm.engine.context import build_context
from cbm.engine.grid import build_grid, group_signs, heading_groups
from cbm.engine.threads import shared_out
from cbm.reference import fold_heading, pair_signs


@numba.njit(cache=True, nogil=True)
def _count(ego_ids, ego_vectors, per_anchor, signs, grid, cos2_sigma1, radius):
    """Accepted quadruples (eq. 8) of the ego objects ``ego_ids`` against one grid."""
    u0, v0, cell, nx, ny = grid.cells
    start, gx, gy, g_anchor, g_check = grid.start, grid.x, grid.y, grid.anchor, grid.check
    total = 0
    for n in range(len(ego_ids)):
        i = ego_ids[n]
        sign_row = signs[i]
        for u in range(i * per_anchor, (i + 1) * per_anchor):
            zx, zy = ego_vectors[u, 0], ego_vectors[u, 1]
            z2 = zx * zx + zy * zy
            zu, zv = zx + zy, zx - zy
            k0 = max(int(math.floor((zu - radius - u0) / cell)), 0)
            k1 = min(int(math.floor((zu + radius - u0) / cell)), nx - 1)
            c0 = max(int(math.floor((zv - radius - v0) / cell)), 0)
            c1 = min(int(math.floor((zv + radius - v0) / cell)), ny - 1)
            for k in range(k0, k1 + 1):
                for v in range(start[k * ny + c0], start[k * ny + c1 + 1] if c1 >= c0 else start[k * ny + c0]):
                    wx, wy = gx[v], gy[v]
                    dot = zx * wx + zy * wy
                    norms = z2 * (wx * wx + wy * wy)
                    total += (((g_check[v] == 0) | (sign_row[g_anchor[v]] == g_check[v]))
                              & (abs(zx - wx) + abs(zy - wy) <= radius) & (norms > 0.0)
                              & (dot * dot >= cos2_sigma1 * norms))
    return total


def floor_seconds(ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray,
                  params: CBMParams) -> tuple[float, int]:
    """(seconds the bare count takes, quadruples it accepts within sigma2) on one trial."""
    cav = se2.apply_boxes(init, cav_boxes)
    ego_heading, cav_heading = fold_heading(ego_boxes[:, 6]), fold_heading(cav[:, 6])
    signs = pair_signs(ego_heading, cav_heading, params.heading).astype(np.int64)
    ego, cav_context = build_context(ego_boxes[:, :2], ego_heading), build_context(cav[:, :2], cav_heading)
    per_anchor = max(len(ego_boxes) - 1, 0)
    groups = heading_groups(ego_heading, signs)
    grids = [build_grid(cav_context, group_signs(signs, g), params.sigma2) for g in groups]
    cos2 = math.cos(params.sigma1_rad) ** 2
    started = time.perf_counter()
    tasks = [lambda part=part, g=g: _count(part, ego.vectors, per_anchor, signs, g, cos2, params.sigma2)
             for group, g in zip(groups, grids) for part in np.array_split(group, tuning.THREADS) if len(part)]
    total = sum(shared_out(tasks))
    return time.perf_counter() - started, int(total)
