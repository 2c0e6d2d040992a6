"""Steps 1-3 as the engine holds them: the CAV boxes in the ego frame, the folded headings and
the signs (``cbm.reference``'s steps 1-2), and every object's context vectors (eq. 6-7,
``cbm.reference.context_vectors``) stacked anchor by anchor, with the extent the join's grid needs."""
from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numba
import numpy as np

from .. import se2
from ..reference import fold_heading, pair_signs


class Context(NamedTuple):
    """All context vectors of one agent: ``vectors[k] = R(theta_anchor)^T (p_member - p_anchor)``."""

    anchor: np.ndarray
    """(M,) index of the object whose local frame the vector is expressed in (i in eq. 6)."""
    member: np.ndarray
    """(M,) index of the neighbour the vector points to (i' in eq. 6)."""
    vectors: np.ndarray
    """(M, 2) the context vectors z_ii' (columns of P_i in eq. 7)."""
    bounds: np.ndarray
    """(N, 4) per object i, the lowest and highest u = x + y, then v = x - y, of its context vectors
    (+inf, -inf without any): the extent of any grid of them (``local_matching.grid``) in O(N)."""


def build_context(xy: np.ndarray, heading: np.ndarray, stop: np.ndarray | None = None) -> Context:
    """Context matrices P_i of eq. 7 for every object, stacked: one row per ordered pair i != i',
    anchor by anchor. Once ``stop[0]`` is set (``cbm.engine.threads.stop_flag``) the rows left are
    not filled: the caller then raises ``Cancelled``."""
    rows = len(xy) * (len(xy) - 1)
    anchor, member, vectors = np.empty(rows, np.int64), np.empty(rows, np.int64), np.empty((rows, 2))
    bounds = np.empty((len(xy), 4))
    _fill_context(np.ascontiguousarray(xy, dtype=float), np.cos(heading), np.sin(heading), anchor, member, vectors,
                  bounds, np.zeros(1, np.uint8) if stop is None else stop)
    return Context(anchor=anchor, member=member, vectors=vectors, bounds=bounds)


@numba.njit(cache=True, nogil=True)
def _fill_context(xy, c, s, anchor, member, vectors, bounds, stop):
    """``vectors[k] = R(theta_i)^T (p_i' - p_i)`` for every ordered pair (i, i'), i != i', and each
    anchor's ``bounds`` of u = x + y and v = x - y over its vectors; anchor by anchor until
    ``stop[0]`` is set."""
    k = 0
    for i in range(len(xy)):
        if stop[0]:
            return
        u0, u1, v0, v1 = np.inf, -np.inf, np.inf, -np.inf
        for m in range(len(xy)):
            if m == i:
                continue
            dx, dy = xy[m, 0] - xy[i, 0], xy[m, 1] - xy[i, 1]
            anchor[k], member[k] = i, m
            x, y = c[i] * dx + s[i] * dy, -s[i] * dx + c[i] * dy
            vectors[k, 0], vectors[k, 1] = x, y
            u0, u1, v0, v1 = min(u0, x + y), max(u1, x + y), min(v0, x - y), max(v1, x - y)
            k += 1
        bounds[i, 0], bounds[i, 1], bounds[i, 2], bounds[i, 3] = u0, u1, v0, v1


@dataclass(frozen=True)
class Prepared:
    """Steps 1-3 of one input: what no threshold changes."""

    cav_boxes: np.ndarray
    """(Nc, 7) CAV boxes in the ego frame after ``init`` (step 1)."""
    ego_heading: np.ndarray
    """(Ne,) folded ego headings (step 2)."""
    cav_heading: np.ndarray
    """(Nc,) folded CAV headings after ``init`` (step 2)."""
    signs: np.ndarray
    """(Ne, Nc) +1 or -1: how the CAV frame is turned against each ego frame (step 2)."""
    ego_context: Context
    cav_context: Context


def prepare(ego: np.ndarray, cav: np.ndarray, init: np.ndarray, heading: str,
            stop: np.ndarray | None = None) -> Prepared:
    """Steps 1-3: the CAV boxes in the ego frame, folded headings, signs and context vectors (their
    building abandoned once ``stop[0]`` is set: ``build_context``)."""
    cav_in_ego = se2.apply_boxes(init, cav)
    ego_heading, cav_heading = fold_heading(ego[:, 6]), fold_heading(cav_in_ego[:, 6])
    signs = aligned_signs(ego_heading, cav_heading) if heading == "align" else pair_signs(ego_heading, cav_heading,
                                                                                             heading)
    return Prepared(cav_in_ego, ego_heading, cav_heading, signs, build_context(ego[:, :2], ego_heading, stop),
                    build_context(cav_in_ego[:, :2], cav_heading, stop))


def aligned_signs(ego_heading: np.ndarray, cav_heading: np.ndarray) -> np.ndarray:
    """``cbm.reference.pair_signs`` with ``mode="align"``, in one pass without (Ne, Nc) temporaries."""
    signs = np.empty((len(ego_heading), len(cav_heading)))
    _fill_signs(np.asarray(ego_heading, dtype=float), np.asarray(cav_heading, dtype=float), signs)
    return signs


@numba.njit(cache=True, nogil=True)
def _fill_signs(ego_heading, cav_heading, signs):
    """``signs[i, j]`` = +1 where |cav_heading[j] - ego_heading[i]| <= pi / 2, else -1."""
    for i in range(len(ego_heading)):
        for j in range(len(cav_heading)):
            signs[i, j] = 1.0 if abs(cav_heading[j] - ego_heading[i]) <= np.pi / 2 else -1.0
