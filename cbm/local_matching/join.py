"""Step 4b of local matching: the join that counts card(L_ij) (paper eq. 7-8, Algorithm 1).

Testing all (Ne Nc)^2 quadruples is what makes the released code dense. Here the join is
output-sensitive and never holds the accepted quadruples of eq. 8: each ego context vector visits
only the cells of the grid (``grid.VectorGrid``) its L1 square covers, and counts card(L_ij) for
every anchor; it lists only the quadruples within sigma3, the voting sets of the consensus. It runs
in parallel over the heading groups (or the parts of a single group), each owning its anchors'
counters, and its lists are joined in a fixed order, so nothing depends on the threads.
"""
from __future__ import annotations

import ctypes
import math
import threading
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numba
import numpy as np

from ..context import Context
from .grid import build_grid, cells, column, group_signs, heading_groups, l1_and_angle

PARALLEL_FROM = 20_000
"""Context vectors per agent from which the join of a single heading group is split over threads."""
GROUPS_APART_FROM = 5_000
"""Context vectors per agent from which the heading groups are shared out between the threads, each
group whole (its grid and its join): one hand-over and one wait in all. Splitting every group
over the threads instead waits for the slower half of each group and of each pair of grids: 0.8x
to 0.95x the time of local matching from 100 to 1000 objects per agent (``bench_steps.py``)."""
THREADS = 2
"""Threads of ``POOL``: the cores of the machine the targets are set on."""
ANCHORS_PER_CHUNK = 64
"""Ego objects whose context vectors are joined together, column by column of the grid (their
counters, 64 rows of Nc, stay in a core's cache)."""
REUSE_RADII = 2.0
"""A kept grid serves radii up to this factor from the one it was built for; beyond it, the cells
would make a window scan many more vectors (or visit many more cells) than a new grid's."""
TRIM_FROM = 32 * 2**20
"""Bytes of votes from which a join, and their grouping, hand the memory freed back to the system
(``trim_freed``)."""
POOL = ThreadPoolExecutor(max_workers=THREADS, thread_name_prefix="cbm")
"""The threads the kernels (numba, without the interpreter lock) share."""


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
def _by_column(ego_ids, chunk, per_anchor, ego_vectors, u0, cell, nx, column_start, order):
    """The context vectors of the ego objects ``ego_ids[chunk:chunk + ANCHORS_PER_CHUNK]`` into
    ``order`` by the grid column their u = x + y falls in (a counting sort); returns how many."""
    last = min(chunk + ANCHORS_PER_CHUNK, len(ego_ids))
    column_start[:] = 0
    for n in range(chunk, last):
        for u in range(ego_ids[n] * per_anchor, (ego_ids[n] + 1) * per_anchor):
            column_start[column(ego_vectors[u, 0] + ego_vectors[u, 1], u0, cell, nx) + 1] += 1
    for k in range(nx):
        column_start[k + 1] += column_start[k]
    for n in range(chunk, last):
        for u in range(ego_ids[n] * per_anchor, (ego_ids[n] + 1) * per_anchor):
            k = column(ego_vectors[u, 0] + ego_vectors[u, 1], u0, cell, nx)
            order[column_start[k]] = u
            column_start[k] += 1
    return (last - chunk) * per_anchor



@numba.njit(cache=True, nogil=True)
def _join(ego_ids, ego_vectors, ego_member, per_anchor, signs, u0, v0, cell, nx, ny, start, gx, gy, g_anchor,
          g_member, g_check, g_slot, cos2_sigma1, sigma2, sigma3, count2, rows, bits):
    """Eq. 7 for the vectors of the ego objects ``ego_ids`` against a grid of (turned) CAV vectors.

    Adds, per anchor pair a, the accepted quadruples within sigma2 to ``count2[a]``; returns those
    within sigma3 packed as ``VoteRows.rows`` (``rows``: an empty array of their dtype; ``bits``:
    the shift of i and b, ``packing``). One pass scans the cells of the wider threshold's window
    (``_query``); a negative threshold skips its test: a sigma2 edit counts again without listing
    the votes, a sigma3 edit lists them without counting. The ego vectors of ``ANCHORS_PER_CHUNK``
    objects at a time are visited column by column of the grid, so consecutive queries read the
    same few columns (from the cache) and the chunk's counters stay in it too.
    """
    n_ego, n_cav = signs.shape
    counting, radius = sigma2 >= 0.0, max(sigma2, sigma3)
    n_votes = 0
    order = np.empty(ANCHORS_PER_CHUNK * per_anchor, np.int64)
    column_start = np.empty(nx + 1, np.int64)
    slots = np.zeros(ANCHORS_PER_CHUNK * 3 * n_cav, np.int32)
    slot_row = np.empty(n_ego, np.int64)
    widest = _widest_column(nx, ny, start)
    for chunk in range(0, len(ego_ids), ANCHORS_PER_CHUNK):
        last = min(chunk + ANCHORS_PER_CHUNK, len(ego_ids))
        for n in range(chunk, last):
            slot_row[ego_ids[n]] = (n - chunk) * 3 * n_cav
        for q in range(_by_column(ego_ids, chunk, per_anchor, ego_vectors, u0, cell, nx, column_start, order)):
            u = order[q]
            zx, zy = ego_vectors[u, 0], ego_vectors[u, 1]
            k0, k1, c0, c1 = cells(zx + zy, zx - zy, radius, u0, v0, cell, nx, ny)
            if sigma3 >= 0.0:
                most = n_votes + 1 + (k1 - k0 + 1) * widest
                while most > len(rows):
                    rows = _grown(rows, n_votes)
                rows[n_votes] = -((np.int64(u // per_anchor) << bits) | ego_member[u]) - 1
                n_votes += 1
            n_votes = _query(zx, zy, u // per_anchor, slot_row[u // per_anchor], signs, k0, k1, c0, c1, ny, start,
                             gx, gy, g_anchor, g_member, g_check, g_slot, cos2_sigma1, sigma2, sigma3, slots, rows,
                             bits, n_votes)
        if counting:
            _add_slots(ego_ids[chunk:last], signs, slots, count2)
    return rows[:n_votes].copy()


@numba.njit(cache=True, nogil=True, inline="always")
def _query(zx, zy, i, slot_row, signs, k0, k1, c0, c1, ny, start, gx, gy, g_anchor, g_member, g_check, g_slot,
           cos2_sigma1, sigma2, sigma3, slots, rows, bits, n_votes):
    """Eq. 7 for one ego vector z of anchor ``i`` against the rows of the cells c0..c1 of the
    columns k0..k1. Each row within sigma2 adds 1 to its slot (``slots``), the row's anchor and
    sign (``_slots``) from ``slot_row`` on, without a branch: which slot counts is settled per
    anchor pair afterwards (``_add_slots``). The few rows within sigma3 whose sign holds against
    anchor ``i`` (``check`` 0 or ``signs[i, b]``) are appended as (CAV anchor b, CAV member j')
    packed in one value, ``b << bits | j'``, in the order of the rows, to ``rows``, grown
    beforehand to hold as many rows as k1 - k0 + 1 columns can (``_widest_column``). Returns the
    new length of ``rows``."""
    sign_row = signs[i]
    z2 = zx * zx + zy * zy
    for k in range(k0, k1 + 1):
        for v in range(start[k * ny + c0], start[k * ny + c1 + 1]):
            l1, angle = l1_and_angle(zx, zy, z2, gx[v], gy[v], cos2_sigma1)
            slots[slot_row + g_slot[v]] += (l1 <= sigma2) & angle
            if (l1 <= sigma3) & angle:
                b = g_anchor[v]
                rows[n_votes] = (np.int64(b) << bits) | g_member[v]
                n_votes += (g_check[v] == 0) | (sign_row[b] == g_check[v])
    return n_votes


@numba.njit(cache=True, nogil=True)
def _widest_column(nx, ny, start):
    """The most grid rows one column holds: ``k`` columns of a window hold at most ``k`` times as many."""
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
def _grown(values, n):
    """``values[:n]`` in an array twice as long."""
    grown = np.empty(2 * len(values), values.dtype)
    grown[:n] = values[:n]
    return grown


def run_join(ego: Context, cav: Context, ego_heading: np.ndarray, signs: np.ndarray, sigma1_rad: float,
             radius: float, sigma2: float, sigma3: float, count2: np.ndarray,
             kept: dict | None = None) -> list[VoteRows]:
    """``_join`` group by group of ego headings, each group's grid built and then joined. From
    ``GROUPS_APART_FROM`` context vectors the groups are shared out between the threads
    (``_groups_apart``); a single group is joined in parts on the threads from ``PARALLEL_FROM``.
    The votes come back as the parts' ``VoteRows``, in a fixed order (not joined into one array:
    that would hold them twice). The grids are built for ``radius`` (at least both thresholds); a
    negative ``sigma2`` counts nothing (``count2`` is not read), a negative ``sigma3`` lists nothing.
    ``kept`` holds the grids between calls on the same contexts: a grid serves any radius (every
    vector of the cells a window covers is tested exactly), kept while its cells suit the radius.
    From ``PARALLEL_FROM`` each group is joined in ``THREADS`` parts, even by one thread: a part's
    vote list, grown and then copied to fit, is then half a group's (whole groups on both threads
    held 63 MB more at once at 1000 objects per agent, dense)."""
    per_anchor = max(len(ego_heading) - 1, 0)
    groups = heading_groups(ego_heading, signs)
    _fresh_grids(kept, radius)
    arguments = (ego, cav, per_anchor, signs, sigma1_rad, radius, sigma2, sigma3, count2, kept)
    parts = THREADS if len(ego.vectors) >= PARALLEL_FROM else 1
    if len(groups) > 1 and len(ego.vectors) >= GROUPS_APART_FROM:
        votes = _groups_apart(groups, arguments, parts)
    elif len(ego.vectors) >= PARALLEL_FROM:
        votes = [rows for k, group in enumerate(groups)
                 for rows in _group_joined(group, k, *arguments, POOL.submit, parts)]
    else:
        votes = [rows for part in _groups_joined(groups, range(len(groups)), arguments, 1).values() for rows in part]
    if sum(part.rows.nbytes for part in votes) >= TRIM_FROM:
        trim_freed()
    return votes


def _groups_joined(groups: list[np.ndarray], indices, arguments: tuple, parts: int) -> dict[int, list[VoteRows]]:
    """The votes of each heading group ``groups[k]``, k taken in turn from ``indices``: its grid
    built (or taken from ``kept``) and joined on the calling thread, in ``parts`` parts of its ego
    objects one after another."""
    return {k: _group_joined(groups[k], k, *arguments, _at_once, parts) for k in indices}


def _groups_apart(groups: list[np.ndarray], arguments: tuple, parts: int) -> list[VoteRows]:
    """The votes of every heading group, in the groups' order, the groups shared out whole between
    the calling thread and one of ``POOL``'s: each takes the next group not yet taken when it is
    done with one. The groups own disjoint ego objects, so their counters never meet."""
    indices = iter(range(len(groups)))
    taking = threading.Lock()

    def taken():
        while True:
            with taking:
                k = next(indices, None)
            if k is None:
                return
            yield k

    theirs = POOL.submit(_groups_joined, groups, taken(), arguments, parts)
    joined = _groups_joined(groups, taken(), arguments, parts)
    joined.update(theirs.result())
    return [rows for k in range(len(groups)) for rows in joined[k]]


def _find_trim():
    """glibc's ``malloc_trim``, or None where the C library has none (or cannot be opened by name)."""
    try:
        return ctypes.CDLL(None).malloc_trim
    except (AttributeError, OSError, TypeError):
        return None


_MALLOC_TRIM = _find_trim()


def trim_freed() -> None:
    """Hands the memory the threads freed (the join's grids and grown vote lists; the votes once
    grouped) back to the system: glibc keeps it resident in the threads' arenas, where what comes
    next never reuses it."""
    if _MALLOC_TRIM is not None:
        _MALLOC_TRIM(0)


def _group_joined(group: np.ndarray, k: int, ego: Context, cav: Context, per_anchor: int, signs: np.ndarray,
                  sigma1_rad: float, radius: float, sigma2: float, sigma3: float, count2: np.ndarray,
                  kept: dict | None, run, parts: int) -> list[VoteRows]:
    """The votes of heading group ``k`` (ego objects ``group``), joined by ``run`` in ``parts`` parts of
    its ego objects, its grid built (or taken from ``kept``) here: without ``kept`` the grid is held
    only by the group's jobs, so it is freed as soon as they have run."""
    grid = _grids([group], k, cav, signs, radius, run, kept)[0]
    n_ego, n_cav = signs.shape
    jobs = _submitted(group, grid, ego, per_anchor, signs, sigma1_rad, sigma2, sigma3, count2, run, parts)
    del grid
    return [VoteRows(job.result(), n_cav, packing(n_ego, n_cav)[1]) for job in jobs]


def _submitted(group: np.ndarray, grid, ego: Context, per_anchor: int, signs: np.ndarray, sigma1_rad: float,
               sigma2: float, sigma3: float, count2: np.ndarray, run, parts: int) -> list:
    """The jobs (``run``) joining the ego objects ``group`` against ``grid``, in ``parts`` parts."""
    dtype, bits = packing(*signs.shape)
    common = (ego.vectors, ego.member, per_anchor, signs, grid.u0, grid.v0, grid.cell, grid.nx, grid.ny,
              grid.start, grid.x, grid.y, grid.anchor, grid.member, grid.check, _slots(grid.anchor, grid.check),
              math.cos(sigma1_rad) ** 2, sigma2, sigma3, count2)
    return [run(_join, part, *common, np.empty(1024, dtype), bits)
            for part in np.array_split(group, parts) if len(part)]


def _fresh_grids(kept: dict | None, radius: float) -> None:
    """Empties ``kept``'s grids unless they were built for a radius within ``REUSE_RADII`` of this
    one (before any thread reads them)."""
    if kept is not None and not radius / REUSE_RADII <= kept.get("grid_radius", -1.0) <= radius * REUSE_RADII:
        kept["grid_radius"], kept["grids"] = radius, {}


def _grids(batch: list[np.ndarray], first: int, cav: Context, signs: np.ndarray, radius: float, run,
           kept: dict | None) -> list:
    """The grids of the heading groups ``batch`` (numbered from ``first``): those in ``kept`` (left
    there by ``_fresh_grids`` for this radius), the others built by ``run`` (and put there)."""
    known = {} if kept is None else kept["grids"]
    jobs = {first + k: run(build_grid, cav, group_signs(signs, g), radius)
            for k, g in enumerate(batch) if first + k not in known}
    known.update({k: job.result() for k, job in jobs.items()})
    return [known.pop(first + k) if kept is None else known[first + k] for k in range(len(batch))]


class Done:
    """A result already computed, read like a future's (``Future.result``)."""

    def __init__(self, value) -> None:
        self.value = value

    def result(self):
        return self.value


def _at_once(function, *args) -> Done:
    return Done(function(*args))

