"""Local matching's join: card(L_ij) of every anchor, and the quadruples within sigma3 (the
voting sets), without ever holding the accepted quadruples of ``cbm.reference.candidate_sets``.

Each ego context vector visits only the cells of the grid (``grid.VectorGrid``) its L1 square
covers, and counts card(L_ij) for every anchor; it lists only the quadruples within sigma3. The
heading groups are shared out between the threads (or one group's ego objects in parts), each
owning its anchors' counters, and the lists come back in a fixed order, so nothing depends on the
threads.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numba
import numpy as np

from . import tuning
from .context import Context, Prepared
from .grid import VectorGrid, build_grid, column, group_signs, heading_groups, l1_and_angle, window
from .threads import TRIM_FROM, check_stop, shared_out, stop_flag, trim_freed

ANCHORS_PER_CHUNK = 64
"""Ego objects whose context vectors are joined together, column by column of the grid (their
counters, 64 rows of Nc, stay in a core's cache)."""
QUERIES_BETWEEN_CHECKS = 1024
"""Queries the join runs between two reads of the stop flag (milliseconds on the densest frames)."""
REUSE_RADII = 2.0
"""A kept grid serves radii up to this factor from the one it was built for; beyond it, the cells
would make a window scan many more vectors (or visit many more cells) than a new grid's."""


class EgoVectors(NamedTuple):
    """The ego's context vectors as the join reads them: ``per_anchor`` rows per object."""

    vectors: np.ndarray
    member: np.ndarray
    per_anchor: int


class Test(NamedTuple):
    """Eq. 8's thresholds as the join applies them: cos^2(sigma1), and the L1 radius of the count
    and of the votes (negative: that pass does not run)."""

    cos2_sigma1: float
    sigma2: float
    sigma3: float


@dataclass
class Grids:
    """The join's grids of one input, one per heading group, kept between calls (``cbm.engine.cache``)
    while they suit the radius: a grid serves any radius (every vector of the cells a window covers
    is tested exactly), but its cells suit one."""

    radius: float = -1.0
    by_group: dict[int, VectorGrid] = field(default_factory=dict)

    def for_radius(self, radius: float) -> Grids:
        """These grids, emptied first unless they were built for a radius within ``REUSE_RADII``."""
        if not radius / REUSE_RADII <= self.radius <= radius * REUSE_RADII:
            self.radius, self.by_group = radius, {}
        return self

    def grid(self, k: int, cav: Context, cav_sign: np.ndarray) -> VectorGrid:
        """Heading group ``k``'s grid, built on first use."""
        if k not in self.by_group:
            self.by_group[k] = build_grid(cav, cav_sign, self.radius)
        return self.by_group[k]


@dataclass(frozen=True)
class VoteRows:
    """The quadruples within sigma3 of one part of the join, in its order, 4 bytes a row where the
    sizes allow (``packing``): per ego vector a head ``-(i << bits | i') - 1`` (its anchor i and
    member i'; written before its window is scanned, kept even when it finds nothing: a branch per
    query costs the join more than the 4 bytes), then one row ``b << bits | j'`` per quadruple (CAV
    anchor b, CAV member j'), whose anchor pair is ``i Nc + b`` and member pair ``i' Nc + j'``."""

    rows: np.ndarray
    n_cav: int
    bits: int

    def __getitem__(self, k: int) -> np.ndarray:
        """``part[0]``, ``part[1]``: the quadruples' anchor and member pair ids, unpacked."""
        head = self.rows < 0
        query = -self.rows[np.maximum.accumulate(np.where(head, np.arange(len(head)), 0))] - 1
        ego = (query >> self.bits, query & ((1 << self.bits) - 1))[k][~head].astype(np.int64)
        cav = (self.rows >> self.bits, self.rows & ((1 << self.bits) - 1))[k][~head]
        return (ego * self.n_cav + cav).astype(np.int32)


def packing(n_ego: int, n_cav: int) -> tuple[type, int]:
    """The dtype of ``VoteRows.rows`` and the shift of i and b: int32 and 16 while every object
    index fits in 15 bits, else int64 and 32."""
    if max(n_ego, n_cav) < 2**15:
        return np.int32, 16
    return np.int64, 32


@numba.njit(cache=True, nogil=True)
def by_column(ego_ids, chunk, ego, cells, column_start, order):
    """The context vectors of the ego objects ``ego_ids[chunk:chunk + ANCHORS_PER_CHUNK]`` into
    ``order`` by the grid column their u = x + y falls in (a counting sort); returns how many."""
    per_anchor, ego_vectors, nx = ego.per_anchor, ego.vectors, cells.nx
    last = min(chunk + ANCHORS_PER_CHUNK, len(ego_ids))
    column_start[:] = 0
    for n in range(chunk, last):
        for u in range(ego_ids[n] * per_anchor, (ego_ids[n] + 1) * per_anchor):
            column_start[column(ego_vectors[u, 0] + ego_vectors[u, 1], cells) + 1] += 1
    for k in range(nx):
        column_start[k + 1] += column_start[k]
    for n in range(chunk, last):
        for u in range(ego_ids[n] * per_anchor, (ego_ids[n] + 1) * per_anchor):
            k = column(ego_vectors[u, 0] + ego_vectors[u, 1], cells)
            order[column_start[k]] = u
            column_start[k] += 1
    return (last - chunk) * per_anchor



@numba.njit(cache=True, nogil=True)
def _join(ego_ids, ego, signs, grid, slot, test, count2, rows, bits, stop):
    """Eq. 8 for the vectors of the ego objects ``ego_ids`` against a grid of (turned) CAV vectors.

    Adds, per anchor pair a, the accepted quadruples within ``test.sigma2`` to ``count2[a]``;
    returns those within ``test.sigma3`` packed as ``VoteRows.rows`` (``rows``: an empty array of
    their dtype; ``bits``: the shift of i and b, ``packing``). One pass scans the cells of the wider
    threshold's window; a negative threshold skips its test: a sigma2 edit counts again without
    listing the votes, a sigma3 edit lists them without counting. The ego vectors of
    ``ANCHORS_PER_CHUNK`` objects at a time are visited column by column of the grid, so
    consecutive queries read the same few columns (from the cache) and the chunk's counters stay
    in it too. Once ``stop[0]`` is set (``threads.stop_flag``) it returns within
    ``QUERIES_BETWEEN_CHECKS`` queries, what it counted and listed incomplete.

    Per query (an ego vector z of anchor i) each grid row within sigma2 adds 1 to its slot among
    its anchor's three counters (``slot``: the row's anchor and sign, ``_slots``), without a branch:
    which slot counts is settled per anchor pair afterwards (``_add_slots``). The few rows within
    sigma3 whose sign holds against anchor i (``check`` 0 or ``signs[i, b]``) are appended as (CAV
    anchor b, CAV member j') packed in one value, ``b << bits | j'``, after the query's head
    ``-(i << bits | i') - 1``, to ``rows``, grown beforehand to hold as many rows as the window's
    columns can (``widest_column``). The bundles are unpacked once, here: numba then keeps their
    arrays in registers through the inner loop.
    """
    n_ego, n_cav = signs.shape
    vectors, member, per_anchor = ego
    cos2_sigma1, sigma2, sigma3 = test
    cells, start, gx, gy, g_anchor, g_member, g_check = grid
    ny = cells.ny
    counting, radius = sigma2 >= 0.0, max(sigma2, sigma3)
    n_votes = 0
    order = np.empty(ANCHORS_PER_CHUNK * per_anchor, np.int64)
    column_start = np.empty(cells.nx + 1, np.int64)
    slots = np.zeros(ANCHORS_PER_CHUNK * 3 * n_cav, np.int32)
    slot_row = np.empty(n_ego, np.int64)
    widest = widest_column(grid)
    for chunk in range(0, len(ego_ids), ANCHORS_PER_CHUNK):
        last = min(chunk + ANCHORS_PER_CHUNK, len(ego_ids))
        for n in range(chunk, last):
            slot_row[ego_ids[n]] = (n - chunk) * 3 * n_cav
        for q in range(by_column(ego_ids, chunk, ego, cells, column_start, order)):
            if q % QUERIES_BETWEEN_CHECKS == 0 and stop[0]:
                return rows[:0].copy()
            u = order[q]
            i = u // per_anchor
            zx, zy = vectors[u, 0], vectors[u, 1]
            k0, k1, c0, c1 = window(zx + zy, zx - zy, radius, cells)
            if sigma3 >= 0.0:
                most = n_votes + 1 + max(k1 - k0 + 1, 0) * widest
                while most > len(rows):
                    rows = grown(rows, n_votes)
                rows[n_votes] = -((np.int64(i) << bits) | member[u]) - 1
                n_votes += 1
            sign_row, first_slot, z2 = signs[i], slot_row[i], zx * zx + zy * zy
            for k in range(k0, k1 + 1):
                for v in range(start[k * ny + c0], start[k * ny + c1 + 1]):
                    l1, angle = l1_and_angle(zx, zy, z2, gx[v], gy[v], cos2_sigma1)
                    slots[first_slot + slot[v]] += (l1 <= sigma2) & angle
                    if (l1 <= sigma3) & angle:
                        b = g_anchor[v]
                        rows[n_votes] = (np.int64(b) << bits) | g_member[v]
                        n_votes += (g_check[v] == 0) | (sign_row[b] == g_check[v])
        if counting:
            _add_slots(ego_ids[chunk:last], signs, slots, count2)
    return rows[:n_votes].copy()


@numba.njit(cache=True, nogil=True)
def widest_column(grid):
    """The most grid rows one column holds: ``k`` columns of a window hold at most ``k`` times as many."""
    nx, ny, start = grid.cells.nx, grid.cells.ny, grid.start
    widest = 0
    for k in range(nx):
        widest = max(widest, start[(k + 1) * ny] - start[k * ny])
    return widest


@numba.njit(cache=True, nogil=True)
def _slots(g_anchor, g_check):
    """Each grid row's slot among its anchor's three counters: ``3 b + check + 1`` (sign -1, fixed
    sign, sign +1)."""
    slot = np.empty(len(g_anchor), np.int32)
    for v in range(len(g_anchor)):
        slot[v] = 3 * g_anchor[v] + g_check[v] + 1
    return slot


@numba.njit(cache=True, nogil=True)
def _add_slots(ego_ids, signs, slots, count2):
    """card(L_ij) of the chunk's ego objects ``ego_ids`` from their slots: per anchor pair (i, b) the
    rows of a fixed sign plus those turned by ``signs[i, b]``; the slots are zeroed for the next
    chunk. A slot holds at most (Ne - 1)(Nc - 1) < 2^31 (``counting.MOST_PAIRS``): int32 suffices."""
    n_cav = signs.shape[1]
    for n in range(len(ego_ids)):
        i, at = ego_ids[n], 3 * n * n_cav
        for b in range(n_cav):
            turned = slots[at + 3 * b + 2] if signs[i, b] > 0 else slots[at + 3 * b]
            count2[i * n_cav + b] += slots[at + 3 * b + 1] + turned
        slots[at:at + 3 * n_cav] = 0


@numba.njit(cache=True, nogil=True)
def grown(values, n):
    """``values[:n]`` in an array twice as long."""
    grown = np.empty(2 * len(values), values.dtype)
    grown[:n] = values[:n]
    return grown


def run_join(prepared: Prepared, sigma1_rad: float, radius: float, sigma2: float, sigma3: float,
             count2: np.ndarray, grids: Grids | None = None) -> list[VoteRows]:
    """``_join`` group by group of ego headings, each group's grid built (or taken from the kept
    ``grids``) for ``radius`` (at least both thresholds) and then joined. A negative ``sigma2``
    counts nothing (``count2`` is not read), a negative ``sigma3`` lists nothing. From
    ``GROUPS_APART_FROM`` context vectors the groups are shared out between the threads, each group
    whole; from ``GROUP_PARTS_FROM`` a group is joined in parts of its ego objects, on the threads
    when it is the only one. The votes come back as the parts' ``VoteRows``, in a fixed order (not
    joined into one array: that would hold them twice). A grid not kept is dropped once its group
    is joined."""
    ego = prepared.ego_context
    groups = heading_groups(prepared.ego_heading, prepared.signs)
    kept = (Grids() if grids is None else grids).for_radius(radius)
    vectors = EgoVectors(ego.vectors, ego.member, max(len(prepared.ego_heading) - 1, 0))
    test = Test(math.cos(sigma1_rad) ** 2, sigma2, sigma3)
    n_parts = tuning.THREADS if len(ego.vectors) >= tuning.GROUP_PARTS_FROM else 1

    def grid(k: int) -> VectorGrid:
        found = kept.grid(k, prepared.cav_context, group_signs(prepared.signs, groups[k]))
        return found if grids is not None else kept.by_group.pop(k)

    def group_joined(k: int) -> list[VoteRows]:
        return joined(groups[k], grid(k), vectors, prepared.signs, test, count2, n_parts)

    if len(groups) == 1 and n_parts > 1:
        only = grid(0)
        tasks = [lambda part=part: joined(part, only, vectors, prepared.signs, test, count2, 1)
                 for part in np.array_split(groups[0], n_parts) if len(part)]
    else:
        tasks = [lambda k=k: group_joined(k) for k in range(len(groups))]
    apart = len(groups) == 1 or len(ego.vectors) >= tuning.GROUPS_APART_FROM
    votes = [rows for part in (shared_out(tasks) if apart else [task() for task in tasks]) for rows in part]
    check_stop()
    if sum(part.rows.nbytes for part in votes) >= TRIM_FROM:
        trim_freed()
    return votes


def joined(ego_ids: np.ndarray, grid: VectorGrid, ego: EgoVectors, signs: np.ndarray, test: Test,
           count2: np.ndarray, n_parts: int) -> list[VoteRows]:
    """The votes of the ego objects ``ego_ids`` joined against ``grid`` in ``n_parts`` parts, one
    after another."""
    n_ego, n_cav = signs.shape
    dtype, bits = packing(n_ego, n_cav)
    slot = _slots(grid.anchor, grid.check)
    stop = stop_flag()
    return [VoteRows(_join(part, ego, signs, grid, slot, test, count2, np.empty(1024, dtype), bits, stop), n_cav, bits)
            for part in np.array_split(ego_ids, n_parts) if len(part)]
