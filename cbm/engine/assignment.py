"""The gated one-to-one assignment of the re-association (``cbm.reassociate``, step 7b beyond the
paper; also the verification's and the track's, ``cbm.hypotheses``, ``cbm.sequence``): candidate pairs
within a gate, their cost as the negative log-likelihood of one object seen twice, and the most pairs
of least summed cost, solved in connected groups so that the work follows the groups' sizes."""
from __future__ import annotations

import math

import numba
import numpy as np
from scipy.optimize import linear_sum_assignment

from .. import se2
from .threads import check_stop

HEADING_SIGMA = math.radians(15.0)
"""Std-dev of the angle between two detections' heading axes of one object (a pi flip is free)."""
SIZE_SIGMA = 0.2
"""Std-dev of the size mismatch ``hypot(log(l_e / l_c), log(w_e / w_c))`` of one object's detections."""
SIZE_GATE = 0.4
"""Largest size mismatch of a pair (the two boxes' lengths or widths about 1.5 times apart)."""
DENSE_BLOCK = 40_000
"""Up to this many entries (gated ego boxes x gated CAV boxes) the assignment is one dense block."""
SMALLEST_SIZE = 0.05
"""Metres. The least length or width a box is compared with."""
UNPAIRED = 1e6
"""Cost of an entry outside the gate in a dense block: above any sum of gated costs."""


def axis_difference(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle between heading axes in [0, pi/2]: headings pi apart (a flipped detection) agree."""
    d = np.abs(se2.wrap_angle(np.asarray(a) - np.asarray(b)))
    return np.minimum(d, np.pi - d)


def size_mismatch(ego: np.ndarray, cav: np.ndarray) -> np.ndarray:
    """``hypot(log(l_e / l_c), log(w_e / w_c))`` of boxes row by row (0 for equal sizes; sizes below
    ``SMALLEST_SIZE`` count as that, so a degenerate box compares without dividing by zero)."""
    e, c = np.maximum(ego[:, 3:5], SMALLEST_SIZE), np.maximum(cav[:, 3:5], SMALLEST_SIZE)
    return np.hypot(*np.log(e / c).T)


def gated_pairs(ego: np.ndarray, cav: np.ndarray, gate: float, sigma: float) -> tuple[np.ndarray, np.ndarray]:
    """Candidate pairs (i, j) whose centres lie within ``gate`` and whose sizes agree within
    ``SIZE_GATE``, and their costs: the negative log-likelihood of one object seen twice,
    ``(d / sigma)^2 + (axis difference / HEADING_SIGMA)^2 + (size mismatch / SIZE_SIGMA)^2``; sorted
    by ego index, then CAV index. (The size mismatch's logarithm is numpy's, as ``size_mismatch``;
    the kernels read C-ordered boxes, so another layout compiles nothing new.)"""
    ego, cav = np.ascontiguousarray(ego, dtype=float), np.ascontiguousarray(cav, dtype=float)
    i, j, d, ratios = near_pairs(ego, cav, gate)
    return scored_pairs(ego, cav, i, j, d, np.hypot(*np.log(ratios).T), sigma)


def gated_assignment(ego: np.ndarray, cav: np.ndarray, gate: float, sigma: float) -> np.ndarray:
    """One-to-one pairs of ego and CAV boxes (both in the ego frame): the most pairs inside the
    gate, and among those the least summed cost (``gated_pairs``), sorted by ego index.

    A small problem is one dense block for ``linear_sum_assignment``; a large one splits into the
    connected groups of candidates that share no box, each solved on its own (a lone candidate is
    its own answer), so the work follows the groups' sizes rather than the product of the box counts.
    A block whose rows each take their own least cost is answered without the solver
    (``row_minima``: the answer the solver gives it).
    """
    candidates, cost = gated_pairs(ego, cav, gate, sigma)
    if len(candidates) == 0:
        return np.zeros((0, 2), dtype=np.intp)
    partner, left, row_ids, row_at, col_ids, col_at, blocks, block_at = assignment_blocks(
        candidates, cost, len(ego), len(cav), DENSE_BLOCK, UNPAIRED)
    for g in range(left):
        check_stop()
        block = blocks[block_at[g]:block_at[g + 1]].reshape(row_at[g + 1] - row_at[g], col_at[g + 1] - col_at[g])
        assign_block(partner, block, *linear_sum_assignment(block), row_ids[row_at[g]:], col_ids[col_at[g]:], UNPAIRED)
    return paired(partner)


@numba.njit(cache=True, nogil=True)
def near_pairs(ego, cav, gate):
    """(i, j, d, size ratios) of the ego and CAV boxes whose centres lie within ``gate``: ``d^2 =
    (x_e - x_c)^2 + (y_e - y_c)^2 <= gate^2`` summed in that order, as a k-d tree's distance matrix
    reads it, and ``d`` its square root; sorted by ego index, then CAV index. The ratios are
    ``l_e / l_c`` and ``w_e / w_c`` of the sizes at least ``SMALLEST_SIZE`` (``size_mismatch``).
    The CAV centres sorted by x bound each ego box's search to the window within the gate in x;
    a first pass counts each ego box's pairs, a second writes them."""
    gate2 = gate * gate
    order = np.argsort(cav[:, 0])
    xs, ys = cav[order, 0], cav[order, 1]
    start, at = np.empty(len(ego), np.intp), np.zeros(len(ego) + 1, np.intp)
    j, d = np.empty(0, np.intp), np.empty(0)
    for e in range(len(ego)):
        start[e] = _window_start(xs, ego[e, 0], gate2)
        at[e + 1] = at[e] + _within(ego[e, 0], ego[e, 1], xs, ys, order, start[e], gate2, j, d, -1)
    n = at[len(ego)]
    i, j, d = np.empty(n, np.intp), np.empty(n, np.intp), np.empty(n)
    for e in range(len(ego)):
        _within(ego[e, 0], ego[e, 1], xs, ys, order, start[e], gate2, j, d, at[e])
        _sort_by_cav(j, d, at[e], at[e + 1])
        i[at[e]:at[e + 1]] = e
    ratios = np.empty((n, 2))
    for k in range(n):
        for c in range(2):
            ratios[k, c] = max(ego[i[k], 3 + c], SMALLEST_SIZE) / max(cav[j[k], 3 + c], SMALLEST_SIZE)
    return i, j, d, ratios


@numba.njit(cache=True, nogil=True)
def _window_start(xs, x, gate2):
    """The first index of the increasing ``xs`` not left of ``x`` by more than the gate
    (``(x - xs[k])^2 > gate2``, the test of the distance's first term)."""
    lo, hi = 0, len(xs)
    while lo < hi:
        mid = (lo + hi) // 2
        if xs[mid] < x and (x - xs[mid]) * (x - xs[mid]) > gate2:
            lo = mid + 1
        else:
            hi = mid
    return lo


@numba.njit(cache=True, nogil=True)
def _within(ex, ey, xs, ys, order, k, gate2, j, d, at):
    """How many of the CAV centres ``(xs, ys)`` (sorted by x; ``order`` their indices) lie within the
    gate of the ego centre ``(ex, ey)``, scanning from ``k`` until ``xs`` is right of it by more than
    the gate; written to ``j[at:]``, ``d[at:]`` unless ``at < 0``."""
    n = 0
    while k < len(xs) and not (xs[k] > ex and (ex - xs[k]) * (ex - xs[k]) > gate2):
        dx, dy = ex - xs[k], ey - ys[k]
        square = dx * dx + dy * dy
        if square <= gate2:
            if at >= 0:
                j[at + n], d[at + n] = order[k], math.sqrt(square)
            n += 1
        k += 1
    return n


@numba.njit(cache=True, nogil=True)
def _sort_by_cav(j, d, lo, hi):
    """Insertion sort of one ego box's few candidates ``j[lo:hi]`` (distinct), ``d`` alongside."""
    for a in range(lo + 1, hi):
        jj, dd, b = j[a], d[a], a
        while b > lo and j[b - 1] > jj:
            j[b], d[b] = j[b - 1], d[b - 1]
            b -= 1
        j[b], d[b] = jj, dd


@numba.njit(cache=True, nogil=True)
def scored_pairs(ego, cav, i, j, d, mismatch, sigma):
    """The candidates ``(i, j)`` at distance ``d`` whose ``mismatch`` is at most ``SIZE_GATE``, as
    (K, 2) pairs, and their costs (``gated_pairs``), each term as numpy evaluates it elementwise."""
    keep = np.flatnonzero(mismatch <= SIZE_GATE)
    pairs, cost = np.empty((len(keep), 2), np.intp), np.empty(len(keep))
    for n in range(len(keep)):
        k = keep[n]
        pairs[n, 0], pairs[n, 1] = i[k], j[k]
        turn = abs((ego[i[k], 6] - cav[j[k], 6] + math.pi) % (2.0 * math.pi) - math.pi)
        a, b, c = d[k] / sigma, min(turn, math.pi - turn) / HEADING_SIGMA, mismatch[k] / SIZE_SIGMA
        cost[n] = a * a + b * b + c * c
    return pairs, cost


@numba.njit(cache=True, nogil=True)
def assign_block(partner, block, r, c, row_ids, col_ids, unpaired):
    """The solver's answer ``r, c`` for one dense ``block`` into ``partner``: ego box ``row_ids[r]``
    pairs with CAV box ``col_ids[c]`` where the block's cost there is inside the gate (below ``unpaired``)."""
    for k in range(len(r)):
        if block[r[k], c[k]] < unpaired:
            partner[row_ids[r[k]]] = col_ids[c[k]]


@numba.njit(cache=True, nogil=True)
def paired(partner):
    """(K, 2) pairs (ego index, CAV ``partner``) of the ego boxes with a partner (not -1), by ego index."""
    n = 0
    for e in range(len(partner)):
        n += partner[e] >= 0
    pairs, n = np.empty((n, 2), np.intp), 0
    for e in range(len(partner)):
        if partner[e] >= 0:
            pairs[n, 0], pairs[n, 1] = e, partner[e]
            n += 1
    return pairs


@numba.njit(cache=True, nogil=True)
def assignment_blocks(candidates, cost, n_ego, n_cav, dense_block, unpaired):
    """What ``gated_assignment`` solves: the CAV partner of each ego box in a group answered without
    the solver (``row_minima``; -1 elsewhere), how many groups are left to it, and their dense
    blocks (``dense_blocks``). All candidates are one group while their distinct ego boxes times
    CAV boxes are at most ``dense_block``, else the connected groups (``connected_groups``)."""
    rows, cols = candidates[:, 0], candidates[:, 1]
    if _distinct(rows, n_ego) * _distinct(cols, n_cav) <= dense_block:
        group, size = np.zeros(len(rows), np.int64), np.full(1, len(rows), np.int64)
    else:
        group, size = connected_groups(rows, cols, n_ego, n_cav)
    partner, solved = row_minima(rows, cols, cost, group, len(size), n_ego, n_cav, unpaired)
    keep = np.flatnonzero(~solved[group])
    number = np.cumsum(~solved) - 1
    row_ids, row_at, col_ids, col_at, blocks, block_at = dense_blocks(
        rows[keep], cols[keep], cost[keep], number[group[keep]], number[-1] + 1, n_ego, n_cav, unpaired)
    return partner, number[-1] + 1, row_ids, row_at, col_ids, col_at, blocks, block_at


@numba.njit(cache=True, nogil=True)
def row_minima(rows, cols, cost, group, n_groups, n_ego, n_cav, unpaired):
    """The groups' answers that need no solver: (CAV partner of each ego box or -1, whether each
    group is answered). A group of one candidate is; so is a group whose dense block has each row
    take the column of its least cost, as ``linear_sum_assignment`` would answer it. The solver
    (shortest augmenting paths, Crouse 2016) reads the block transposed when it is taller than
    wide and takes the rows in order; while every row's least cost is unique and in a column no
    earlier row took, each path is that one step and leaves the duals of the columns at 0, so the
    next row reads its own costs as they are. Unique is tested on the costs less the group's least
    one, which some releases of the solver read (unique there is unique in the costs themselves),
    and against the ``unpaired`` entries too."""
    n_rows, n_cols = _group_counts(rows, group, n_groups, n_ego), _group_counts(cols, group, n_groups, n_cav)
    lowest = np.full(n_groups, np.inf)
    for k in range(len(rows)):
        lowest[group[k]] = min(lowest[group[k]], cost[k])
    tall = n_cols < n_rows
    least = np.full(n_ego + n_cav, np.inf)
    for k in range(len(rows)):
        row = n_ego + cols[k] if tall[group[k]] else rows[k]
        least[row] = min(least[row], cost[k])
    best, solved = np.full(n_ego + n_cav, -1, np.intp), np.ones(n_groups, np.bool_)
    for k in range(len(rows)):
        g = group[k]
        row, column = (n_ego + cols[k], rows[k]) if tall[g] else (rows[k], n_ego + cols[k])
        if cost[k] - lowest[g] == least[row] - lowest[g]:
            unique = best[row] < 0 and best[column] < 0 and least[row] - lowest[g] < unpaired - lowest[g]
            solved[g] = solved[g] and unique
            best[row], best[column] = column, row
    partner = np.full(n_ego, -1, np.intp)
    for k in range(len(rows)):
        if solved[group[k]] and best[rows[k]] == n_ego + cols[k]:
            partner[rows[k]] = cols[k]
    return partner, solved


@numba.njit(cache=True, nogil=True)
def _group_counts(values, group, n_groups, n):
    """How many distinct ``values`` in ``[0, n)`` each group holds."""
    counts, seen = np.zeros(n_groups, np.int64), np.zeros(n, np.bool_)
    for k in range(len(values)):
        if not seen[values[k]]:
            seen[values[k]] = True
            counts[group[k]] += 1
    return counts


@numba.njit(cache=True, nogil=True)
def _distinct(values, n):
    """How many distinct ``values`` in ``[0, n)`` there are."""
    seen, count = np.zeros(n, np.bool_), 0
    for value in values:
        if not seen[value]:
            seen[value], count = True, count + 1
    return count


@numba.njit(cache=True, nogil=True)
def dense_blocks(rows, cols, cost, group, n_groups, n_ego, n_cav, unpaired):
    """Each group's dense block for the assignment: the boxes its candidates name, in increasing
    order (``row_ids[row_at[g]:row_at[g + 1]]``, ``col_ids`` likewise), and the block of their costs
    (``blocks[block_at[g]:block_at[g + 1]]``, row by row; ``unpaired`` where no candidate is)."""
    start = np.zeros(n_groups + 1, np.int64)
    for k in range(len(rows)):
        start[group[k] + 1] += 1
    start = np.cumsum(start)
    members, fill = np.empty(len(rows), np.int64), start[:-1].copy()
    for k in range(len(rows)):
        members[fill[group[k]]] = k
        fill[group[k]] += 1
    row_ids, col_ids = np.empty(len(rows), np.int64), np.empty(len(rows), np.int64)
    row_at, col_at = np.zeros(n_groups + 1, np.int64), np.zeros(n_groups + 1, np.int64)
    block_at = np.zeros(n_groups + 1, np.int64)
    for g in range(n_groups):
        here = members[start[g]:start[g + 1]]
        row_at[g + 1] = row_at[g] + _sorted_distinct(rows, here, row_ids[row_at[g]:])
        col_at[g + 1] = col_at[g] + _sorted_distinct(cols, here, col_ids[col_at[g]:])
        block_at[g + 1] = block_at[g] + (row_at[g + 1] - row_at[g]) * (col_at[g + 1] - col_at[g])
    blocks = np.full(block_at[n_groups], unpaired)
    local_row, local_col = np.empty(n_ego, np.int64), np.empty(n_cav, np.int64)
    for g in range(n_groups):
        for n in range(row_at[g], row_at[g + 1]):
            local_row[row_ids[n]] = n - row_at[g]
        for n in range(col_at[g], col_at[g + 1]):
            local_col[col_ids[n]] = n - col_at[g]
        width = col_at[g + 1] - col_at[g]
        for k in members[start[g]:start[g + 1]]:
            blocks[block_at[g] + local_row[rows[k]] * width + local_col[cols[k]]] = cost[k]
    return row_ids, row_at, col_ids, col_at, blocks, block_at


@numba.njit(cache=True, nogil=True)
def _sorted_distinct(values, at, out):
    """The distinct ``values[at]`` in increasing order into ``out``; returns how many."""
    if len(at) == 1:
        out[0] = values[at[0]]
        return 1
    found = np.sort(values[at])
    n = 0
    for value in found:
        if n == 0 or out[n - 1] != value:
            out[n] = value
            n += 1
    return n


@numba.njit(cache=True, nogil=True)
def _root(parent, node):
    """The root of ``node``'s tree in the union-find forest ``parent`` (halving the path on the way)."""
    while parent[node] != node:
        parent[node] = parent[parent[node]]
        node = parent[node]
    return node


@numba.njit(cache=True, nogil=True)
def connected_groups(rows, cols, n_ego, n_cav):
    """(group of each candidate (row, col), candidates in each group): the connected groups of boxes
    linked through shared candidates (union-find over the ego boxes and, after them, the CAV
    boxes), numbered in order of first appearance. A group of one candidate is a candidate whose
    boxes are in no other candidate: it pairs as it is."""
    parent = np.arange(n_ego + n_cav)
    for k in range(len(rows)):
        a, b = _root(parent, rows[k]), _root(parent, n_ego + cols[k])
        if a != b:
            parent[max(a, b)] = min(a, b)
    number = np.full(n_ego + n_cav, -1, np.int64)
    group, size = np.empty(len(rows), np.int64), np.zeros(len(rows), np.int64)
    groups = 0
    for k in range(len(rows)):
        root = _root(parent, rows[k])
        if number[root] < 0:
            number[root], groups = groups, groups + 1
        group[k] = number[root]
        size[group[k]] += 1
    return group, size[:groups]
