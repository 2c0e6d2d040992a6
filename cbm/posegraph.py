"""More than two agents: a joint estimate of every CAV's pose that keeps them consistent (``cbm-graph``).

With an ego and CAVs 1..n, CBM calibrates each CAV to the ego (edge ego-i) and, where two CAVs
share objects, CAV j to CAV i (edge i-j). Each edge is a measured SE(2) transform weighted by its
match count; the pose graph finds the CAV->ego transforms ``X_i`` (the ego fixed at the identity)
that minimise

    sum_edges w * || v(Z_0i^-1 X_i) ||^2_W  +  sum_edges w * || v(Z_ij^-1 X_i^-1 X_j) ||^2_W

by Gauss-Newton on (x, y, theta) per CAV, ``v`` the (x, y, yaw) of a transform and
``W = diag(1, 1, ROTATION_WEIGHT)``. An edge enters only when CBM estimated a pose from at least
``MIN_EDGE_PAIRS`` pairs; a CAV the edges do not link to the ego keeps its own CBM estimate.

    from cbm.posegraph import match_graph
    result = match_graph(ego_boxes, cav_boxes, init, params, peers=[peer_trial, ...])
"""
from __future__ import annotations

import dataclasses
import itertools
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from . import se2
from .estimate import residuals
from .params import CBMParams
from .pipeline import match
from .result import MatchResult

ROTATION_WEIGHT = 100.0
"""m^2/rad^2: one radian of an edge's yaw residual costs as much as 10 m of its position residual."""
MIN_EDGE_PAIRS = 3
"""An edge needs a CBM estimate from at least this many matched pairs."""
ITERATIONS = 20
STEP = 1e-6
"""Finite-difference step of the Jacobian (metres / radians)."""


class Peer(Protocol):
    """Another CAV of the frame as the pose graph reads it (an ``evaluation.scenario.Trial`` fits)."""

    ego_boxes: np.ndarray
    cav_boxes: np.ndarray
    init: np.ndarray


@dataclass(frozen=True)
class Edge:
    """A measured transform ``Z`` from node ``b``'s frame to node ``a``'s (node 0 is the ego)."""

    a: int
    b: int
    Z: np.ndarray
    weight: float


def edge_of(a: int, b: int, result: MatchResult) -> Edge | None:
    """The edge a CBM result gives, or None when it has too few pairs to count."""
    if not result.estimated or len(result.pairs) < MIN_EDGE_PAIRS:
        return None
    return Edge(a, b, result.transform, float(len(result.pairs)))


def solve(start: Sequence[np.ndarray], edges: Sequence[Edge]) -> list[np.ndarray]:
    """The CAV->ego transforms of nodes 1..n that best agree with ``edges`` (Gauss-Newton), from
    ``start`` (n transforms); nodes the edges do not link to the ego keep their start."""
    linked = _linked_to_ego(len(start), edges)
    free = [i for i in range(1, len(start) + 1) if i in linked]
    if not free:
        return [np.array(T) for T in start]
    x = np.concatenate([_vector(start[i - 1]) for i in free])
    for _ in range(ITERATIONS):
        r, J = _residuals(x, free, edges), _jacobian(x, free, edges)
        step = np.linalg.lstsq(J, -r, rcond=None)[0]
        x = x + step
        if np.linalg.norm(step) < 1e-9:
            break
    solved = {i: se2.make(*x[3 * k:3 * k + 3]) for k, i in enumerate(free)}
    return [solved.get(i, np.array(start[i - 1])) for i in range(1, len(start) + 1)]


def match_graph(ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray, params: CBMParams | None = None,
                *, peers: Sequence[Peer] = ()) -> MatchResult:
    """CBM on this ego/CAV pair, then the pose graph over it and the ``peers`` (the frame's other
    CAV trials): the result's transform is this CAV's pose in the joint solution. Without peers it
    is CBM's result."""
    started = time.perf_counter()
    own = match(ego_boxes, cav_boxes, init, params)
    if not peers:
        return own
    cavs = [(cav_boxes, init), *((peer.cav_boxes, peer.init) for peer in peers)]
    results = [own, *(match(peer.ego_boxes, peer.cav_boxes, peer.init, params) for peer in peers)]
    edges = [edge_of(0, i + 1, result) for i, result in enumerate(results)]
    for i, j in itertools.combinations(range(len(cavs)), 2):
        between = se2.inverse(cavs[i][1]) @ cavs[j][1]
        edges.append(edge_of(i + 1, j + 1, match(cavs[i][0], cavs[j][0], between, params)))
    kept = [edge for edge in edges if edge is not None]
    joint = solve([result.transform for result in results], kept)[0]
    estimated = own.estimated or 1 in _linked_to_ego(len(cavs), kept)
    result = _with_transform(own, joint, ego_boxes, cav_boxes, estimated)
    return dataclasses.replace(result, timings={**own.timings, "total": time.perf_counter() - started})


def _with_transform(result: MatchResult, T: np.ndarray, ego_boxes: np.ndarray, cav_boxes: np.ndarray,
                    estimated: bool) -> MatchResult:
    """``result`` with the joint transform (and its pairs' residuals under it)."""
    pairs = np.asarray(result.pairs, dtype=int).reshape(-1, 2)
    distance = residuals(T, cav_boxes[pairs[:, 1], :2], ego_boxes[pairs[:, 0], :2])
    return dataclasses.replace(result, transform=T, residuals=distance, estimated=estimated)


def _linked_to_ego(n: int, edges: Sequence[Edge]) -> set[int]:
    """The nodes a path of edges joins to the ego (node 0)."""
    linked, grew = {0}, True
    while grew:
        grew = False
        for edge in edges:
            if (edge.a in linked) != (edge.b in linked):
                linked |= {edge.a, edge.b}
                grew = True
    return linked - {0}


def _vector(T: np.ndarray) -> np.ndarray:
    return np.array([*se2.translation_of(T), se2.yaw_of(T)])


def _residuals(x: np.ndarray, free: list[int], edges: Sequence[Edge]) -> np.ndarray:
    """Every edge's weighted residual ``sqrt(w W) v(Z^-1 X_a^-1 X_b)`` stacked."""
    poses = {0: np.eye(3), **{i: se2.make(*x[3 * k:3 * k + 3]) for k, i in enumerate(free)}}
    scale = np.sqrt(np.array([1.0, 1.0, ROTATION_WEIGHT]))
    rows = []
    for edge in edges:
        if edge.a not in poses or edge.b not in poses:
            continue
        error = se2.inverse(edge.Z) @ se2.inverse(poses[edge.a]) @ poses[edge.b]
        rows.append(np.sqrt(edge.weight) * scale * _vector(error))
    return np.concatenate(rows)


def _jacobian(x: np.ndarray, free: list[int], edges: Sequence[Edge]) -> np.ndarray:
    """Forward-difference Jacobian of ``_residuals`` (at most a few CAVs: 3n columns)."""
    base = _residuals(x, free, edges)
    columns = []
    for k in range(len(x)):
        moved = x.copy()
        moved[k] += STEP
        columns.append((_residuals(moved, free, edges) - base) / STEP)
    return np.stack(columns, axis=1)
