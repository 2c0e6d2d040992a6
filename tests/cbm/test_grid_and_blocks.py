"""The join's grid, the sorted blocks and the contexts equal plain numpy constructions of the same
arrays (stable sorts), on scenes with many equal keys and with all three signs of a heading group."""
import math

import numpy as np
import pytest

from cbm.engine.candidates import sorted_blocks
from cbm.engine.context import aligned_signs, build_context
from cbm.engine.grid import build_grid
from cbm.reference import context_vectors, pair_signs


def _scene(kind: str, n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(xy, heading): random, or a 5 m lattice with headings of quarter turns (many equal keys and
    signed zeros among them)."""
    rng = np.random.default_rng(seed)
    if kind == "random":
        return rng.uniform(-80.0, 80.0, (n, 2)), rng.uniform(-math.pi / 2, math.pi / 2, n)
    side = int(math.ceil(math.sqrt(n)))
    xy = 5.0 * np.stack(np.divmod(np.arange(n), side), axis=1).astype(float)
    return xy, rng.choice([0.0, math.pi / 2, -math.pi / 2], n)


def _stable_blocks(vectors: np.ndarray, member: np.ndarray, per_anchor: int) -> list[np.ndarray]:
    """The blocks sorted by x + y with numpy's stable argsort."""
    key = vectors[:, 0] + vectors[:, 1]
    order = (np.argsort(key.reshape(-1, per_anchor), axis=1, kind="stable")
             + per_anchor * np.arange(len(key) // per_anchor)[:, None]).ravel()
    return [key[order], vectors[order, 0], vectors[order, 1], member[order]]


def _reference_grid(vectors, anchor, member, cav_sign, u0, v0, cell, nx, ny) -> list[np.ndarray]:
    """Rows (vector by vector, sign +1 before -1) stably sorted by column-major cell."""
    turns = [(v, s) for v in range(len(vectors)) for s in ((int(cav_sign[anchor[v]]),) if cav_sign[anchor[v]]
                                                             else (1, -1))]
    source, sign = np.array([t[0] for t in turns]), np.array([t[1] for t in turns], float)
    x, y = sign * vectors[source, 0], sign * vectors[source, 1]
    kx = np.minimum(np.floor((x + y - u0) / cell).astype(int), nx - 1)
    ky = np.minimum(np.floor((x - y - v0) / cell).astype(int), ny - 1)
    key = kx * ny + ky
    order = np.argsort(key, kind="stable")
    start = np.concatenate([[0], np.cumsum(np.bincount(key, minlength=nx * ny))])
    check = np.where(cav_sign[anchor[source]] != 0, 0, sign)
    return [start, x[order], y[order], anchor[source][order], member[source][order], check[order]]


@pytest.mark.parametrize("kind", ["random", "lattice"])
@pytest.mark.parametrize("n", [1, 2, 40])
def test_sorted_blocks_equal_a_stable_sort(kind, n):
    xy, heading = _scene(kind, n, seed=n)
    context = build_context(xy, heading)
    blocks = sorted_blocks(context, n)
    got = [blocks.key, blocks.x, blocks.y, blocks.member]
    want = _stable_blocks(context.vectors, context.member, max(n - 1, 1))
    for g, w in zip(got, want):
        assert g.dtype == w.dtype and np.array_equal(g, w)
        assert np.array_equal(np.signbit(g), np.signbit(w))


def test_sorted_blocks_keep_equal_keys_and_signed_zeros_in_row_order():
    xy = np.array([[0.0, 0.0], [1.0, -1.0], [-1.0, 1.0], [2.0, -2.0], [0.0, 3.0], [3.0, 0.0]])
    context = build_context(xy, np.zeros(len(xy)))
    blocks = sorted_blocks(context, len(xy))
    assert blocks.member[:5].tolist() == [1, 2, 3, 4, 5]
    assert np.array_equal(blocks.member, _stable_blocks(context.vectors, context.member, len(xy) - 1)[3])


@pytest.mark.parametrize("kind", ["random", "lattice"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_grid_equals_a_stable_sort_of_the_turned_rows(kind, seed):
    xy, heading = _scene(kind, 60, seed)
    context = build_context(xy, heading)
    cav_sign = np.random.default_rng(seed).choice([-1.0, 0.0, 1.0], len(xy))
    grid = build_grid(context, cav_sign, 3.0)
    want = _reference_grid(context.vectors, context.anchor, context.member, cav_sign, *grid.cells)
    got = [grid.start, grid.x, grid.y, grid.anchor, grid.member, grid.check]
    for name, g, w in zip(["start", "x", "y", "anchor", "member", "check"], got, want):
        assert np.array_equal(g, w), name
    assert grid.cells.u0 == min(want[1] + want[2]) and grid.cells.v0 == min(want[1] - want[2])


@pytest.mark.parametrize("kind", ["random", "lattice"])
def test_context_rows_are_the_reference_context_vectors_of_every_ordered_pair(kind):
    xy, heading = _scene(kind, 30, seed=3)
    context = build_context(xy, heading)
    anchor, member = np.divmod(np.arange(30 * 30), 30)
    anchor, member = anchor[anchor != member], member[anchor != member]
    assert np.array_equal(context.anchor, anchor) and np.array_equal(context.member, member)
    want = np.concatenate([np.delete(context_vectors(xy, heading, i), i, axis=0) for i in range(30)])
    assert np.array_equal(context.vectors, want)


def test_pair_signs_turn_the_cav_frame_past_a_quarter_turn_exactly_at_the_boundary():
    ego = np.array([math.pi / 2, -math.pi / 2, 0.0, 0.3, -1.2])
    cav = np.array([0.0, math.pi / 2, -math.pi / 2, 0.3 - math.pi / 2, 1.0, -0.9])
    want = np.where(np.abs(cav[None, :] - ego[:, None]) <= np.pi / 2, 1.0, -1.0)
    got = pair_signs(ego, cav, "align")
    assert got.shape == (5, 6) and np.array_equal(got, want) and np.array_equal(aligned_signs(ego, cav), want)
    assert got[0, 0] == 1.0 and got[0, 2] == -1.0 and got[1, 1] == -1.0
    assert np.array_equal(pair_signs(ego, cav, "fold"), np.ones((5, 6)))
