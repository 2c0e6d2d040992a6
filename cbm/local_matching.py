"""Context similarity-based coarse matching (paper eq. 7-8 and Algorithm 1).

For an anchor pair (i, j) a candidate (i', j') is accepted when the context vectors
``z = z_ii'`` and ``w = z_jj'`` satisfy

    arccos(|z . w| / (|z| |w|)) <= sigma1      and      ||z - w||_1 <= sigma2        (eq. 7)

Testing all (Ne Nc)^2 quadruples is what makes the released code dense. Here the join is
output-sensitive and never holds the accepted quadruples of eq. 8:

- the ego objects go in four groups of neighbouring headings; for each group the CAV context
  vectors lie in a grid (``VectorGrid``), already turned by the sign they have against it, over
  u = x + y and v = x - y, where the L1 diamond around an ego vector z is an axis-aligned square:
  z meets only the vectors of the cells that square covers, one run of cells per column;
- that join counts card(L_ij) for every anchor and lists only the quadruples within sigma3, the
  voting sets of the consensus (``count_candidates``); it runs in parallel over parts of each
  group, each part owning its anchors' counters, and its lists are joined in a fixed order, so
  nothing depends on the threads;
- the members of one L_ij are listed again when the selection asks for them
  (``CandidateSets.members``): a window sliding over both anchors' vectors sorted by x + y, O(N).

Pair ids are ``i * Nc + j`` throughout.
"""
from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numba
import numpy as np

from .context import Context

CELLS_PER_RADIUS = 3
"""Grid cells per L1 radius: smaller cells cut the vectors a query scans, at more cells to visit."""
MAX_CELLS = 1 << 21
"""Most grid cells (16 MB of row offsets); a wider scene gets wider cells."""
CELLS_PER_ROW = 4
"""Most grid cells per vector: a sparse scene gets wider cells rather than many empty ones."""
MOST_PAIRS = 2**31 - 1
"""Most ego x CAV pairs: the voting quadruples are listed as 32-bit pair ids (half the memory)."""
MARGIN = 1e-6
"""Metres added to every search window, so that rounding never hides a vector eq. 7 accepts;
each vector in the window is then tested exactly."""
PARALLEL_FROM = 20_000
"""Context vectors per agent from which the joins are split over threads."""
THREADS = 2
HEADING_GROUPS = 4
"""Groups of ego objects by heading, each joined against the CAV vectors turned by their sign for it."""
ANCHORS_PER_CHUNK = 64
"""Ego objects whose context vectors are joined together, column by column of the grid (their
counters, 64 rows of Nc, stay in a core's cache)."""
POOL = ThreadPoolExecutor(max_workers=THREADS, thread_name_prefix="cbm")
"""The threads the kernels (numba, without the interpreter lock) share."""


@dataclass(frozen=True)
class VectorGrid:
    """CAV context vectors, each turned by the sign it has against a group of ego objects, in
    square cells of side ``cell`` over u = x + y, v = x - y (where the L1 diamond of eq. 7 is an
    axis-aligned square), column by column: cell (ku, kv) holds rows
    ``start[ku * ny + kv]:start[ku * ny + kv + 1]``, so the cells kv0..kv1 of one column are one
    run of rows; (u0, v0) is the grid's corner. ``check[r]`` is 0 where the sign holds
    for the whole group, else the sign that row carries (the row's vector is there twice, once per
    sign, to be checked per ego object)."""

    u0: float
    v0: float
    cell: float
    nx: int
    ny: int
    start: np.ndarray
    x: np.ndarray
    y: np.ndarray
    anchor: np.ndarray
    member: np.ndarray
    check: np.ndarray


def build_grid(cav: Context, cav_sign: np.ndarray, radius: float) -> VectorGrid:
    """The grid of the CAV vectors turned by ``cav_sign`` (per CAV object: +1, -1, or 0 when the
    sign varies within the group), cells ``radius / CELLS_PER_RADIUS`` wide (wider past ``MAX_CELLS``)."""
    x, y, anchor, member, check = _signed_rows(cav.vectors, cav.anchor, cav.member, cav_sign.astype(np.int64))
    if len(x) == 0:
        return VectorGrid(0.0, 0.0, 1.0, 1, 1, np.zeros(2, np.int64), x, y, anchor, member, check)
    u, v = x + y, x - y
    u0, v0 = float(u.min()), float(v.min())
    width, height = float(u.max()) - u0, float(v.max()) - v0
    most_cells = min(MAX_CELLS, CELLS_PER_ROW * len(x) + 1)
    cell = max(radius / CELLS_PER_RADIUS, math.sqrt((width + 1.0) * (height + 1.0) / most_cells), 1e-9)
    nx, ny = int(width // cell) + 1, int(height // cell) + 1
    start = np.zeros(nx * ny + 1, np.int64)
    rows = (x, y, anchor, member, check)
    grid = tuple(np.empty_like(values) for values in rows)
    _bucket(*rows, u0, v0, cell, nx, ny, start, *grid)
    return VectorGrid(u0, v0, cell, nx, ny, start, *grid)


@numba.njit(cache=True, nogil=True)
def _signed_rows(vectors, anchor, member, cav_sign):
    """Rows of (sign * x, sign * y, anchor, member, check): one per vector of a CAV object with a
    fixed sign (check 0), two (check +1 and -1) per vector of one whose sign varies."""
    n = 0
    for v in range(len(vectors)):
        n += 1 if cav_sign[anchor[v]] != 0 else 2
    x, y = np.empty(n), np.empty(n)
    out_anchor, out_member, check = np.empty(n, np.int64), np.empty(n, np.int64), np.empty(n, np.int64)
    r = 0
    for v in range(len(vectors)):
        fixed = cav_sign[anchor[v]]
        for sign in (1, -1):
            if fixed != 0 and sign != fixed:
                continue
            x[r], y[r] = sign * vectors[v, 0], sign * vectors[v, 1]
            out_anchor[r], out_member[r], check[r] = anchor[v], member[v], 0 if fixed != 0 else sign
            r += 1
    return x, y, out_anchor, out_member, check


@numba.njit(cache=True, nogil=True)
def _bucket(x, y, anchor, member, check, u0, v0, cell, nx, ny, start, gx, gy, g_anchor, g_member, g_check):
    """Counting sort of the rows by cell of (x + y, x - y) (column-major), keeping their order inside a cell."""
    cell_of = np.empty(len(x), np.int64)
    for v in range(len(x)):
        kx = min(int(math.floor((x[v] + y[v] - u0) / cell)), nx - 1)
        ky = min(int(math.floor((x[v] - y[v] - v0) / cell)), ny - 1)
        cell_of[v] = kx * ny + ky
        start[cell_of[v] + 1] += 1
    for c in range(nx * ny):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    for v in range(len(x)):
        row = fill[cell_of[v]]
        gx[row], gy[row], g_anchor[row], g_member[row], g_check[row] = x[v], y[v], anchor[v], member[v], check[v]
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
def _cells(zu, zv, radius, u0, v0, cell, nx, ny):
    """Columns k0..k1 and, in each, cells c0..c1 of the square max(|du|, |dv|) <= radius around z:
    the L1 diamond |dx| + |dy| <= radius in the grid's coordinates u = x + y, v = x - y. No column
    (k1 < k0) when the square misses the grid."""
    k0 = max(int(math.floor((zu - radius - MARGIN - u0) / cell)), 0)
    k1 = min(int(math.floor((zu + radius + MARGIN - u0) / cell)), nx - 1)
    c0 = max(int(math.floor((zv - radius - MARGIN - v0) / cell)), 0)
    c1 = min(int(math.floor((zv + radius + MARGIN - v0) / cell)), ny - 1)
    if c1 < c0:
        return 0, -1, 0, 0
    return k0, k1, c0, c1


@numba.njit(cache=True, nogil=True)
def _by_column(ego_ids, chunk, per_anchor, ego_vectors, u0, cell, nx, column_start, order):
    """The context vectors of the ego objects ``ego_ids[chunk:chunk + ANCHORS_PER_CHUNK]`` into
    ``order`` by the grid column their u = x + y falls in (a counting sort); returns how many."""
    last = min(chunk + ANCHORS_PER_CHUNK, len(ego_ids))
    column_start[:] = 0
    for n in range(chunk, last):
        for u in range(ego_ids[n] * per_anchor, (ego_ids[n] + 1) * per_anchor):
            column_start[_column(ego_vectors[u, 0] + ego_vectors[u, 1], u0, cell, nx) + 1] += 1
    for k in range(nx):
        column_start[k + 1] += column_start[k]
    for n in range(chunk, last):
        for u in range(ego_ids[n] * per_anchor, (ego_ids[n] + 1) * per_anchor):
            k = _column(ego_vectors[u, 0] + ego_vectors[u, 1], u0, cell, nx)
            order[column_start[k]] = u
            column_start[k] += 1
    return (last - chunk) * per_anchor


@numba.njit(cache=True, nogil=True, inline="always")
def _column(zu, u0, cell, nx):
    return min(max(int(math.floor((zu - u0) / cell)), 0), nx - 1)


@numba.njit(cache=True, nogil=True)
def _join(ego_ids, ego_vectors, ego_member, per_anchor, signs, u0, v0, cell, nx, ny, start, gx, gy, g_anchor,
          g_member, g_check, cos2_sigma1, radius, sigma2, sigma3, count2, list_votes):
    """Eq. 7 for the vectors of the ego objects ``ego_ids`` against a grid of (turned) CAV vectors.

    Adds, per anchor pair a, the accepted quadruples within sigma2 to ``count2[a]``; with
    ``list_votes``, returns those within sigma3 as (anchor, member) rows. A grid row with ``check``
    s counts only where ``signs[i, j] == s``. The ego vectors of ``ANCHORS_PER_CHUNK`` objects at a
    time are visited column by column of the grid, so consecutive queries read the same few
    columns (from the cache) and the chunk's counters stay in it too. The counting loop combines
    the tests of ``_accepts`` without branches (the data decide no jump in it); the votes are listed
    in a second, narrower pass over the cells within sigma3.
    """
    n_cav = signs.shape[1]
    capacity = 1024 if list_votes else 0
    vote_anchor, vote_member, n_votes = np.empty(capacity, np.int32), np.empty(capacity, np.int32), 0
    order = np.empty(ANCHORS_PER_CHUNK * per_anchor, np.int64)
    column_start = np.empty(nx + 1, np.int64)
    for chunk in range(0, len(ego_ids), ANCHORS_PER_CHUNK):
        for q in range(_by_column(ego_ids, chunk, per_anchor, ego_vectors, u0, cell, nx, column_start, order)):
            u = order[q]
            i = u // per_anchor
            sign_row = signs[i]
            row = i * n_cav
            zx, zy = ego_vectors[u, 0], ego_vectors[u, 1]
            z2 = zx * zx + zy * zy
            zu, zv = zx + zy, zx - zy
            k0, k1, c0, c1 = _cells(zu, zv, radius, u0, v0, cell, nx, ny)
            for k in range(k0, k1 + 1):
                for v in range(start[k * ny + c0], start[k * ny + c1 + 1]):
                    b, wx, wy = g_anchor[v], gx[v], gy[v]
                    l1 = abs(zx - wx) + abs(zy - wy)
                    dot = zx * wx + zy * wy
                    squared_norms = z2 * (wx * wx + wy * wy)
                    ok = (((g_check[v] == 0) | (sign_row[b] == g_check[v])) & (l1 <= radius)
                          & (squared_norms > 0.0) & (dot * dot >= cos2_sigma1 * squared_norms))
                    count2[row + b] += ok & (l1 <= sigma2)
            if not list_votes:
                continue
            k0, k1, c0, c1 = _cells(zu, zv, sigma3, u0, v0, cell, nx, ny)
            for k in range(k0, k1 + 1):
                for v in range(start[k * ny + c0], start[k * ny + c1 + 1]):
                    b = g_anchor[v]
                    if g_check[v] != 0 and sign_row[b] != g_check[v]:
                        continue
                    if _accepts(zx, zy, gx[v], gy[v], cos2_sigma1, sigma3) < 0.0:
                        continue
                    if n_votes == capacity:
                        capacity *= 2
                        grown_anchor, grown_member = np.empty(capacity, np.int32), np.empty(capacity, np.int32)
                        grown_anchor[:n_votes], grown_member[:n_votes] = vote_anchor, vote_member
                        vote_anchor, vote_member = grown_anchor, grown_member
                    vote_anchor[n_votes] = row + b
                    vote_member[n_votes] = ego_member[u] * n_cav + g_member[v]
                    n_votes += 1
    return vote_anchor[:n_votes], vote_member[:n_votes]


def heading_groups(ego_heading: np.ndarray, signs: np.ndarray) -> list[np.ndarray]:
    """Ego objects in ``HEADING_GROUPS`` groups of neighbouring headings (one group when no sign
    is -1): within a group most CAV objects have one sign against every member."""
    if not np.any(signs < 0):
        return [np.arange(len(ego_heading))] if len(ego_heading) else []
    order = np.argsort(ego_heading, kind="stable")
    return [group for group in np.array_split(order, HEADING_GROUPS) if len(group)]


def group_signs(signs: np.ndarray, group: np.ndarray) -> np.ndarray:
    """(Nc,) the sign of each CAV object against every ego object of ``group``, 0 where it varies."""
    rows = signs[group]
    low, high = rows.min(axis=0), rows.max(axis=0)
    return np.where(low == high, low, 0.0)


def _run_join(ego: Context, cav: Context, ego_heading: np.ndarray, signs: np.ndarray, sigma1_rad: float,
              radius: float, sigma2: float, sigma3: float, count2: np.ndarray,
              list_votes: bool) -> tuple[np.ndarray, np.ndarray]:
    """``_join`` group by group of ego headings. In parallel, ``THREADS`` groups' grids are built
    at a time, then their ego objects are joined in parts; the votes come back in a fixed order."""
    per_anchor = max(len(ego_heading) - 1, 0)
    groups = heading_groups(ego_heading, signs)
    parallel = len(ego.vectors) >= PARALLEL_FROM
    run = POOL.submit if parallel else _at_once
    votes = []
    for first in range(0, len(groups), THREADS if parallel else 1):
        batch = groups[first:first + (THREADS if parallel else 1)]
        grids = [grid.result() for grid in [run(build_grid, cav, group_signs(signs, g), radius) for g in batch]]
        jobs = []
        for group, grid in zip(batch, grids):
            common = (ego.vectors, ego.member, per_anchor, signs, grid.u0, grid.v0, grid.cell, grid.nx, grid.ny,
                      grid.start, grid.x, grid.y, grid.anchor, grid.member, grid.check, math.cos(sigma1_rad) ** 2,
                      radius, sigma2, sigma3, count2, list_votes)
            parts = np.array_split(group, THREADS) if parallel else [group]
            jobs += [run(_join, part, *common) for part in parts if len(part)]
        votes += [job.result() for job in jobs]
    if not votes:
        return np.zeros(0, np.int32), np.zeros(0, np.int32)
    return np.concatenate([v[0] for v in votes]), np.concatenate([v[1] for v in votes])


class _Done:
    """A result already computed, read like a future's."""

    def __init__(self, value) -> None:
        self.value = value

    def result(self):
        return self.value


def _at_once(function, *args) -> _Done:
    return _Done(function(*args))


@dataclass(frozen=True)
class SortedBlocks:
    """One agent's context vectors, each anchor's block of ``per_anchor`` rows sorted by the key
    ``x + y``: two vectors within L1 distance r have keys within r, and the key spreads the
    vectors along the streets of either axis, where x alone would pile them up."""

    key: np.ndarray
    x: np.ndarray
    y: np.ndarray
    member: np.ndarray
    per_anchor: int


def sorted_blocks(context: Context, n_objects: int) -> SortedBlocks:
    """Each anchor's context vectors sorted by ``x + y`` (for the sliding windows of ``members_into``)."""
    per_anchor = max(n_objects - 1, 0)
    shape = (len(context.vectors) // max(per_anchor, 1), per_anchor)
    key = (context.vectors[:, 0] + context.vectors[:, 1]).reshape(shape)
    order = np.argsort(key, axis=1, kind="stable")
    key, x, y, member = (np.ascontiguousarray(np.take_along_axis(values.reshape(shape), order, axis=1).ravel())
                         for values in (key, context.vectors[:, 0], context.vectors[:, 1], context.member))
    return SortedBlocks(key, x, y, member, per_anchor)


@numba.njit(cache=True, nogil=True)
def members_into(i, j, sign, e_key, ex, ey, e_member, per_ego, c_key, cx, cy, c_member, per_cav, n_cav, cos2_sigma1,
                 sigma2, out):
    """The members of L_ij (eq. 8) into ``out``, the anchor pair last; returns how many.

    Both anchors' blocks are sorted by ``x + y``, so the CAV vectors (turned by ``sign``) whose key
    lies within sigma2 of an ego vector's form a window that only slides forward: O(N) per anchor
    pair plus the vectors in the windows.
    """
    size = 0
    lo_j, hi_j = j * per_cav, (j + 1) * per_cav
    window = 0
    for u in range(i * per_ego, (i + 1) * per_ego):
        zx, zy, zk = ex[u], ey[u], e_key[u]
        while window < per_cav and _turned(c_key, lo_j, hi_j, window, sign) < zk - sigma2 - MARGIN:
            window += 1
        k = window
        while k < per_cav:
            if _turned(c_key, lo_j, hi_j, k, sign) > zk + sigma2 + MARGIN:
                break
            v = lo_j + k if sign > 0 else hi_j - 1 - k
            if _accepts(zx, zy, sign * cx[v], sign * cy[v], cos2_sigma1, sigma2) >= 0.0:
                out[size] = e_member[u] * n_cav + c_member[v]
                size += 1
            k += 1
    if size:
        out[size] = i * n_cav + j
        size += 1
    return size


@numba.njit(cache=True, nogil=True, inline="always")
def _turned(key, lo, hi, k, sign):
    """The k-th smallest key of the block lo..hi-1 after turning its vectors by ``sign``."""
    return key[lo + k] if sign > 0 else -key[hi - 1 - k]


@dataclass(frozen=True)
class CandidateSets:
    """The candidate sets L_ij of every anchor (eq. 8): their sizes, and their members on demand."""

    count: np.ndarray
    """(Ne * Nc,) card(L_ij), the anchor pair included when the set is not empty."""
    lookup: tuple
    """``members_into``'s arguments after (i, j, sign) and before ``out``."""
    signs: np.ndarray
    """(Ne, Nc) how the CAV frame is turned against each ego frame (``cbm.context.pair_signs``)."""

    @property
    def width(self) -> int:
        """The largest card(L_ij) (at least 1): the room a kernel needs for any one set."""
        return max(1, int(self.count.max())) if len(self.count) else 1

    def members(self, anchor: int) -> np.ndarray:
        """Pair ids of L_ij for ``anchor = i * Nc + j``, in increasing order."""
        n_cav = self.signs.shape[1]
        i, j = divmod(int(anchor), n_cav)
        out = np.empty(int(self.count[anchor]) + 1, np.int64)
        size = members_into(i, j, float(self.signs[i, j]), *self.lookup, out)
        return np.sort(out[:size])


def count_candidates(ego: Context, cav: Context, ego_heading: np.ndarray, signs: np.ndarray, sigma1_rad: float,
                     sigma2: float, sigma3: float | None) -> tuple[CandidateSets, np.ndarray, np.ndarray]:
    """card(L_ij) at sigma2 for every anchor, and (with ``sigma3``) the (anchor, member) rows of every
    quadruple within sigma3 (the voting sets of eq. 9 without their own pairs), from one join."""
    n_ego, n_cav = signs.shape
    if n_ego * n_cav > MOST_PAIRS:
        raise ValueError(f"cbm.match: {n_ego} x {n_cav} boxes make more than {MOST_PAIRS} pairs (the voting "
                         "sets keep pair ids in 32 bits)")
    count2 = np.zeros(n_ego * n_cav, np.int64)
    radius = sigma2 if sigma3 is None else max(sigma2, sigma3)
    vote_anchor, vote_member = _run_join(ego, cav, ego_heading, signs, sigma1_rad, radius, sigma2,
                                         -1.0 if sigma3 is None else sigma3, count2, sigma3 is not None)
    count2 += count2 > 0
    candidates = CandidateSets(count2, member_lookup(ego, cav, n_ego, n_cav, sigma1_rad, sigma2), signs)
    return candidates, vote_anchor, vote_member


def member_lookup(ego: Context, cav: Context, n_ego: int, n_cav: int, sigma1_rad: float, sigma2: float) -> tuple:
    """What ``members_into`` needs after (i, j, sign) to list any anchor's candidate set."""
    e, c = sorted_blocks(ego, n_ego), sorted_blocks(cav, n_cav)
    return (e.key, e.x, e.y, e.member, e.per_anchor, c.key, c.x, c.y, c.member, c.per_anchor, n_cav,
            math.cos(sigma1_rad) ** 2, sigma2)
