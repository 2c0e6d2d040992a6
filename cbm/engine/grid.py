"""The grid local matching's join searches (``cbm.reference.similar``, eq. 8).

The ego objects go in ``HEADING_GROUPS`` groups of neighbouring headings; for each group the CAV
context vectors lie in a grid (``VectorGrid``), already turned by the sign they have against it,
over u = x + y and v = x - y, where the L1 diamond around an ego vector z is an axis-aligned
square: z meets only the vectors of the cells that square covers, one run of cells per column.
``accepts`` and ``l1_and_angle`` test one quadruple as the reference does, without square roots.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numba
import numpy as np

from .context import Context
from .threads import check_stop, stop_flag

CELLS_PER_RADIUS = 3
"""Grid cells per L1 radius: smaller cells cut the vectors a query scans, at more cells to visit."""
MAX_CELLS = 1 << 21
"""Most grid cells (16 MB of row offsets); a wider scene gets wider cells."""
CELLS_PER_ROW = 4
"""Most grid cells per vector: a sparse scene gets wider cells rather than many empty ones."""
MARGIN = 1e-6
"""Metres added to every search window, so that rounding never hides a vector eq. 8 accepts;
each vector in the window is then tested exactly."""
MOST_ROWS = 2**31 - 1
"""Most grid rows (twice the CAV context vectors at most): the grid's offsets are int32."""
HEADING_GROUPS = 4
"""Groups of ego objects by heading, each joined against the CAV vectors turned by their sign for it."""


class Cells(NamedTuple):
    """Square cells of side ``cell`` over u = x + y, v = x - y from the corner (u0, v0), ``nx``
    columns of ``ny`` cells, numbered column by column."""

    u0: float
    v0: float
    cell: float
    nx: int
    ny: int


class VectorGrid(NamedTuple):
    """CAV context vectors, each turned by the sign it has against a group of ego objects, in the
    ``cells`` column by column: cell (ku, kv) holds rows ``start[ku * ny + kv]:start[ku * ny + kv + 1]``,
    so the cells kv0..kv1 of one column are one run of rows. ``check[r]`` is 0 where the sign holds
    for the whole group, else the sign that row carries (the row's vector is there twice, once per
    sign, to be checked per ego object)."""

    cells: Cells
    start: np.ndarray
    x: np.ndarray
    y: np.ndarray
    anchor: np.ndarray
    member: np.ndarray
    check: np.ndarray


def build_grid(cav: Context, cav_sign: np.ndarray, radius: float) -> VectorGrid:
    """The grid of the CAV vectors turned by ``cav_sign`` (per CAV object: +1, -1, or 0 when the
    sign varies within the group), cells ``radius / CELLS_PER_RADIUS`` wide (wider past ``MAX_CELLS``).
    A counting sort that turns the vectors as it places them (their extent comes from
    ``Context.bounds``). Raises ``Cancelled`` once the computation is abandoned (``threads.stoppable``)."""
    if 2 * len(cav.vectors) > MOST_ROWS:
        raise ValueError(f"cbm.match: {len(cav.vectors)} CAV context vectors make more grid rows than {MOST_ROWS}")
    sign = cav_sign.astype(np.int64)
    n, u0, v0, u1, v1 = _extent(cav.bounds, sign, len(cav.vectors) // max(len(cav.bounds), 1))
    if n == 0:
        empty, ids = np.zeros(0), np.zeros(0, np.int32)
        return VectorGrid(Cells(0.0, 0.0, 1.0, 1, 1), np.zeros(2, np.int32), empty, empty.copy(), ids, ids.copy(),
                          np.zeros(0, np.int8))
    width, height = u1 - u0, v1 - v0
    most_cells = min(MAX_CELLS, CELLS_PER_ROW * n + 1)
    cell = max(radius / CELLS_PER_RADIUS, math.sqrt((width + 1.0) * (height + 1.0) / most_cells), 1e-9)
    cells = Cells(float(u0), float(v0), float(cell), int(width // cell) + 1, int(height // cell) + 1)
    return VectorGrid(cells, *_place(cav, sign, n, cells))


@numba.njit(cache=True, nogil=True)
def _extent(bounds, cav_sign, per_anchor):
    """(rows, lowest u, lowest v, highest u, highest v) of the turned vectors in u = x + y, v = x - y:
    one row per vector of a CAV object with a fixed sign, two (sign +1 and -1) where it varies. From
    each object's ``Context.bounds``: turned by -1, a vector's u and v change sign exactly."""
    n, u0, v0, u1, v1 = 0, np.inf, np.inf, -np.inf, -np.inf
    for a in range(len(bounds)):
        if cav_sign[a] >= 0:
            u0, u1, v0, v1 = min(u0, bounds[a, 0]), max(u1, bounds[a, 1]), min(v0, bounds[a, 2]), max(v1, bounds[a, 3])
            n += per_anchor
        if cav_sign[a] <= 0:
            u0, u1 = min(u0, -bounds[a, 1]), max(u1, -bounds[a, 0])
            v0, v1 = min(v0, -bounds[a, 3]), max(v1, -bounds[a, 2])
            n += per_anchor
    return n, u0, v0, u1, v1


def _place(cav: Context, cav_sign: np.ndarray, n: int, cells: Cells) -> tuple[np.ndarray, ...]:
    """Counting sort of the turned rows by cell of (x + y, x - y) (column-major), keeping the order
    of the vectors (sign +1 before -1) inside a cell; ``check`` is 0 for a fixed sign, else the
    row's sign. The vectors come anchor by anchor, ``len(vectors) // len(cav_sign)`` each (as
    ``build_context`` stacks them). Three passes over them: ``_cells`` finds each row's cell, whose
    rows are counted (``start`` shifted by two); each row's source (twice its vector's index, plus 1
    for the turn by -1 of a varying sign) goes to its cell's next free place (``start`` shifted by
    one, so that it ends unshifted); then ``_written`` writes the rows in order from their sources,
    one random write a row instead of five. Returns (start, x, y, anchor, member, check). Offsets and
    sources fit int32 (``MOST_ROWS``). Each pass stops early once the computation is abandoned
    (``threads.stop_flag``); ``check_stop`` then raises before the next reads what it left."""
    per_anchor, stop = len(cav.vectors) // len(cav_sign), stop_flag()
    key = _cell_of_rows(cav.vectors, cav_sign, per_anchor, n, cells, stop)
    check_stop()
    start, source = _sources(key, cav_sign, per_anchor, n, cells, stop)
    check_stop()
    written = _written(source, cav, cav_sign, stop)
    check_stop()
    return (start,) + written


@numba.njit(cache=True, nogil=True)
def _sources(key, cav_sign, per_anchor, n, cells, stop):
    """``_place``'s count of the rows per cell and each row's source at its cell's place:
    (start, source)."""
    start = np.zeros(cells.nx * cells.ny + 2, np.int32)
    for r in range(n):
        start[key[r] + 2] += 1
    total = 0
    for k in range(2, len(start)):
        total += start[k]
        start[k] = total
    source = np.empty(n, np.int32)
    r = 0
    for a in range(len(cav_sign)):
        if stop[0]:
            break
        for v in range(a * per_anchor, (a + 1) * per_anchor):
            for turn in range(1 if cav_sign[a] != 0 else 2):
                source[start[key[r] + 1]] = 2 * v + turn
                start[key[r] + 1] += 1
                r += 1
    return start[:-1], source


@numba.njit(cache=True, nogil=True)
def _written(source, cav, cav_sign, stop):
    """The grid's rows (x, y, anchor, member, check) in the order of their sources (``_place``): the
    vector turned by its anchor's sign, or where the sign varies by +1 (even source) or -1 (odd),
    ``check`` then that sign. ``anchor`` and ``member`` are CAV objects, fewer than 2^31
    (``local_matching.MOST_PAIRS`` bounds Ne x Nc), so int32 holds them; ``check`` is -1, 0 or 1
    (int8): 25 bytes a row instead of 40. Stops early once ``stop[0]`` is set."""
    vectors, anchor, member = cav.vectors, cav.anchor, cav.member
    n = len(source)
    gx, gy = np.empty(n), np.empty(n)
    g_anchor, g_member, g_check = np.empty(n, np.int32), np.empty(n, np.int32), np.empty(n, np.int8)
    for row in range(n):
        if stop[0]:
            break
        v, turn = source[row] >> 1, source[row] & 1
        b = anchor[v]
        fixed = cav_sign[b]
        sign = fixed if fixed != 0 else 1 - 2 * turn
        gx[row], gy[row], g_anchor[row], g_member[row] = sign * vectors[v, 0], sign * vectors[v, 1], b, member[v]
        g_check[row] = 0 if fixed != 0 else sign
    return gx, gy, g_anchor, g_member, g_check


@numba.njit(cache=True, nogil=True)
def _cell_of_rows(vectors, cav_sign, per_anchor, n, cells, stop):
    """The cell of each of the ``n`` turned rows, in their order: a fixed sign's rows in one loop per
    anchor (which the compiler vectorises), a varying sign's as +1 then -1; anchor by anchor until
    ``stop[0]`` is set."""
    u0, v0, cell, nx, ny = cells
    key = np.empty(n, np.int32)
    r = 0
    for a in range(len(cav_sign)):
        if stop[0]:
            break
        lo, s = a * per_anchor, cav_sign[a]
        if s != 0:
            for v in range(lo, lo + per_anchor):
                key[r + v - lo] = _cell(s * vectors[v, 0], s * vectors[v, 1], u0, v0, cell, nx, ny)
            r += per_anchor
            continue
        for v in range(lo, lo + per_anchor):
            key[r] = _cell(vectors[v, 0], vectors[v, 1], u0, v0, cell, nx, ny)
            key[r + 1] = _cell(-vectors[v, 0], -vectors[v, 1], u0, v0, cell, nx, ny)
            r += 2
    return key


@numba.njit(cache=True, nogil=True, inline="always")
def _cell(x, y, u0, v0, cell, nx, ny):
    """The column-major cell of the vector (x, y) in the grid of corner (u0, v0)."""
    return (min(int(math.floor((x + y - u0) / cell)), nx - 1) * ny
            + min(int(math.floor((x - y - v0) / cell)), ny - 1))


@numba.njit(cache=True, nogil=True, inline="always")
def accepts(zx, zy, wx, wy, cos2_sigma1, radius):
    """L1 distance of z and w when eq. 8 accepts them, else -1; the angle test is evaluated as
    (z.w)^2 >= cos^2(sigma1) |z|^2 |w|^2 (sigma1 <= 90 degrees), without square roots or arccos."""
    l1 = abs(zx - wx) + abs(zy - wy)
    if l1 > radius:
        return -1.0
    squared_norms = (zx * zx + zy * zy) * (wx * wx + wy * wy)
    dot = zx * wx + zy * wy
    if squared_norms <= 0.0 or dot * dot < cos2_sigma1 * squared_norms:
        return -1.0
    return l1


@numba.njit(cache=True, nogil=True, inline="always")
def l1_and_angle(zx, zy, z2, wx, wy, cos2_sigma1):
    """Eq. 8 for z and w without a branch: their L1 distance, and whether the angle test accepts
    them (as in ``accepts``; ``z2`` is |z|^2)."""
    dot = zx * wx + zy * wy
    squared_norms = z2 * (wx * wx + wy * wy)
    return abs(zx - wx) + abs(zy - wy), (squared_norms > 0.0) & (dot * dot >= cos2_sigma1 * squared_norms)


@numba.njit(cache=True, nogil=True, inline="always")
def window(zu, zv, radius, cells):
    """Columns k0..k1 and, in each, cells c0..c1 of the square max(|du|, |dv|) <= radius around z:
    the L1 diamond |dx| + |dy| <= radius in the grid's coordinates u = x + y, v = x - y. No column
    (k1 < k0) when the square misses the grid."""
    u0, v0, cell, nx, ny = cells
    k0 = max(int(math.floor((zu - radius - MARGIN - u0) / cell)), 0)
    k1 = min(int(math.floor((zu + radius + MARGIN - u0) / cell)), nx - 1)
    c0 = max(int(math.floor((zv - radius - MARGIN - v0) / cell)), 0)
    c1 = min(int(math.floor((zv + radius + MARGIN - v0) / cell)), ny - 1)
    if c1 < c0:
        return 0, -1, 0, 0
    return k0, k1, c0, c1



@numba.njit(cache=True, nogil=True, inline="always")
def column(zu, cells):
    """The grid column of u = ``zu``, clamped to the grid."""
    u0, cell, nx = cells.u0, cells.cell, cells.nx
    return min(max(int(math.floor((zu - u0) / cell)), 0), nx - 1)



def heading_groups(ego_heading: np.ndarray, signs: np.ndarray) -> list[np.ndarray]:
    """Ego objects in ``HEADING_GROUPS`` groups of neighbouring headings (one group when no sign
    is -1): within a group most CAV objects have one sign against every member. The groups are
    ``np.array_split``'s of the objects in heading order: the first ``n % HEADING_GROUPS`` one larger."""
    if not np.any(signs < 0):
        return [np.arange(len(ego_heading))] if len(ego_heading) else []
    order = np.argsort(ego_heading, kind="stable")
    each, extra = divmod(len(order), HEADING_GROUPS)
    ends = [k * each + min(k, extra) for k in range(HEADING_GROUPS + 1)]
    return [order[a:b] for a, b in zip(ends, ends[1:]) if b > a]


def group_signs(signs: np.ndarray, group: np.ndarray) -> np.ndarray:
    """(Nc,) the sign of each CAV object against every ego object of ``group``, 0 where it varies."""
    return _group_signs(np.ascontiguousarray(signs), group)


@numba.njit(cache=True, nogil=True)
def _group_signs(signs, group):
    """``group_signs`` of the (Ne, Nc) ``signs`` and the rows ``group`` (at least one), row by row."""
    low, high = signs[group[0]].copy(), signs[group[0]].copy()
    for i in group[1:]:
        for j in range(signs.shape[1]):
            low[j], high[j] = min(low[j], signs[i, j]), max(high[j], signs[i, j])
    for j in range(len(low)):
        if low[j] != high[j]:
            low[j] = 0.0
    return low
