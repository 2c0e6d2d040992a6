"""Heading handling (step 2) and intra-agent context construction (paper eq. 5-6)."""
from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from .params import HeadingMode


def fold_heading(yaw: np.ndarray) -> np.ndarray:
    """Fold headings into (-pi/2, pi/2], as the released code does before building contexts."""
    folded = np.mod(np.asarray(yaw, dtype=float) + np.pi / 2, np.pi) - np.pi / 2
    return np.where(folded == -np.pi / 2, np.pi / 2, folded)


def pair_signs(ego_heading: np.ndarray, cav_heading: np.ndarray, mode: HeadingMode) -> np.ndarray:
    """(Ne, Nc) sign applied to a CAV object's local frame when it is compared with an ego object.

    Headings are folded. ``fold``: always +1, so an object near +-90 degrees may fold to opposite
    directions for the two agents and its local frame flips. ``align``: -1 where the two folded
    headings differ by more than 90 degrees, which turns the CAV frame by pi so that it lies within
    90 degrees of the ego frame it is compared with; a co-visible object's frames then never flip.
    """
    if mode == "fold":
        return np.ones((len(ego_heading), len(cav_heading)))
    signs = np.empty((len(ego_heading), len(cav_heading)))
    _fill_signs(np.asarray(ego_heading, dtype=float), np.asarray(cav_heading, dtype=float), signs)
    return signs


@numba.njit(cache=True, nogil=True)
def _fill_signs(ego_heading, cav_heading, signs):
    """``signs[i, j]`` = +1 where |cav_heading[j] - ego_heading[i]| <= pi / 2, else -1 (one pass,
    no (Ne, Nc) temporaries)."""
    for i in range(len(ego_heading)):
        for j in range(len(cav_heading)):
            signs[i, j] = 1.0 if abs(cav_heading[j] - ego_heading[i]) <= np.pi / 2 else -1.0


@dataclass(frozen=True)
class Context:
    """All context vectors of one agent: ``vectors[k] = R(theta_anchor)^T (p_member - p_anchor)``."""

    anchor: np.ndarray
    """(M,) index of the object whose local frame the vector is expressed in (i in eq. 5)."""
    member: np.ndarray
    """(M,) index of the neighbour the vector points to (i' in eq. 5)."""
    vectors: np.ndarray
    """(M, 2) the context vectors z_ii' (columns of P_i in eq. 6)."""
    bounds: np.ndarray
    """(N, 4) per object i, the lowest and highest u = x + y, then v = x - y, of its context vectors
    (+inf, -inf without any): the extent of any grid of them (``local_matching.grid``) in O(N)."""


def build_context(xy: np.ndarray, heading: np.ndarray) -> Context:
    """Context matrices P_i of eq. 6 for every object, stacked: one row per ordered pair i != i',
    anchor by anchor."""
    rows = len(xy) * (len(xy) - 1)
    anchor, member, vectors = np.empty(rows, np.int64), np.empty(rows, np.int64), np.empty((rows, 2))
    bounds = np.empty((len(xy), 4))
    _fill_context(np.ascontiguousarray(xy, dtype=float), np.cos(heading), np.sin(heading), anchor, member, vectors,
                  bounds)
    return Context(anchor=anchor, member=member, vectors=vectors, bounds=bounds)


@numba.njit(cache=True, nogil=True)
def _fill_context(xy, c, s, anchor, member, vectors, bounds):
    """``vectors[k] = R(theta_i)^T (p_i' - p_i)`` for every ordered pair (i, i'), i != i', and each
    anchor's ``bounds`` of u = x + y and v = x - y over its vectors."""
    k = 0
    for i in range(len(xy)):
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
