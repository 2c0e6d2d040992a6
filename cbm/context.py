"""Heading handling (step 2) and intra-agent context construction (paper eq. 5-6)."""
from __future__ import annotations

from dataclasses import dataclass

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
    difference = np.abs(cav_heading[None, :] - ego_heading[:, None])
    return np.where(difference <= np.pi / 2, 1.0, -1.0)


@dataclass(frozen=True)
class Context:
    """All context vectors of one agent: ``vectors[k] = R(theta_anchor)^T (p_member - p_anchor)``."""

    anchor: np.ndarray
    """(M,) index of the object whose local frame the vector is expressed in (i in eq. 5)."""
    member: np.ndarray
    """(M,) index of the neighbour the vector points to (i' in eq. 5)."""
    vectors: np.ndarray
    """(M, 2) the context vectors z_ii' (columns of P_i in eq. 6)."""


def build_context(xy: np.ndarray, heading: np.ndarray) -> Context:
    """Context matrices P_i of eq. 6 for every object, stacked: one row per ordered pair i != i'."""
    n = len(xy)
    anchor, member = np.nonzero(~np.eye(n, dtype=bool))
    offset = xy[member] - xy[anchor]
    c, s = np.cos(heading[anchor]), np.sin(heading[anchor])
    vectors = np.stack([c * offset[:, 0] + s * offset[:, 1], -s * offset[:, 0] + c * offset[:, 1]], axis=1)
    return Context(anchor=anchor, member=member, vectors=vectors)
