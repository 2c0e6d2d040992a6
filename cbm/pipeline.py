"""CBM, steps 1-7 of the paper's section III, from two box lists and a wrong relative pose."""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from . import se2
from .consensus import PairSets, sets_within
from .context import Context, build_context, fold_heading, pair_signs
from .estimate import residuals, robust_se2
from .inputs import checked_boxes, checked_transform
from .local_matching import accepted_quadruples
from .params import CBMParams
from .result import MatchResult
from .selection import select


@dataclass(frozen=True)
class Sets:
    """Everything CBM knows before it picks an anchor (steps 1-4 and the sets of step 5)."""

    params: CBMParams
    ego_xy: np.ndarray
    """(Ne, 2) ego centres."""
    cav_xy: np.ndarray
    """(Nc, 2) CAV centres pre-transformed into the ego frame by ``init`` (step 1)."""
    ego_heading: np.ndarray
    """(Ne,) folded ego headings (step 2)."""
    cav_heading: np.ndarray
    """(Nc,) folded CAV headings after ``init`` (step 2)."""
    signs: np.ndarray
    """(Ne, Nc) +1 or -1: how the CAV frame is turned against each ego frame (step 2)."""
    ego_context: Context
    cav_context: Context
    candidates: PairSets
    """L_ij of every anchor (eq. 8), grouped by pair id ``i * Nc + j``."""
    voted_by: PairSets
    """Row m: the pairs whose voting set holds pair m (empty when consensus is off)."""

    @property
    def rule(self) -> str | None:
        return self.params.consensus_rule if self.params.consensus else None


def build_sets(ego: np.ndarray, cav: np.ndarray, init: np.ndarray, params: CBMParams,
               timings: dict[str, float] | None = None) -> Sets:
    """Steps 1-4 and the candidate and voting sets, for checked inputs."""
    timings = {} if timings is None else timings
    started = time.perf_counter()
    cav_in_ego = se2.apply_boxes(init, cav)
    ego_xy, cav_xy = ego[:, :2], cav_in_ego[:, :2]
    ego_heading, cav_heading = fold_heading(ego[:, 6]), fold_heading(cav_in_ego[:, 6])
    signs = pair_signs(ego_heading, cav_heading, params.heading)
    ego_context, cav_context = build_context(ego_xy, ego_heading), build_context(cav_xy, cav_heading)
    t = time.perf_counter()
    timings["context"] = t - started

    radius = max(params.sigma2, params.sigma3) if params.consensus else params.sigma2
    quads = accepted_quadruples(ego_context, cav_context, ego_heading, cav_heading, signs, params.sigma1_rad, radius)
    timings["local_matching"] = time.perf_counter() - t
    t = time.perf_counter()

    n_pairs = len(ego) * len(cav)
    candidates = sets_within(quads, params.sigma2, n_pairs)
    voted_by = sets_within(quads, params.sigma3, n_pairs, by_member=True) if params.consensus else PairSets.empty(n_pairs)
    timings["candidate_sets"] = time.perf_counter() - t
    return Sets(params, ego_xy, cav_xy, ego_heading, cav_heading, signs, ego_context, cav_context, candidates, voted_by)


def checked_inputs(ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray | None,
                   params: CBMParams | None) -> tuple[np.ndarray, np.ndarray, np.ndarray, CBMParams]:
    """The arguments of ``match`` checked, with defaults filled in."""
    params = CBMParams() if params is None else params
    if not isinstance(params, CBMParams):
        raise ValueError(f"params must be a CBMParams, got {type(params).__name__}")
    init = np.eye(3) if init is None else checked_transform("init", init)
    return checked_boxes("ego_boxes", ego_boxes), checked_boxes("cav_boxes", cav_boxes), init, params


def match(ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray | None = None,
          params: CBMParams | None = None) -> MatchResult:
    """Match ego and CAV boxes by their context and refine the CAV->ego transform.

    ``ego_boxes`` (Ne, 7) are in the ego frame, ``cav_boxes`` (Nc, 7) in the CAV frame, rows
    ``x, y, z, length, width, height, yaw``; ``init`` is the (wrong) CAV->ego transform from
    localization (identity when None).
    """
    started = time.perf_counter()
    ego, cav, init, params = checked_inputs(ego_boxes, cav_boxes, init, params)
    timings: dict[str, float] = {}
    return match_sets(build_sets(ego, cav, init, params, timings), init, timings, started)


def match_sets(sets: Sets, init: np.ndarray, timings: dict[str, float] | None = None,
               started: float | None = None) -> MatchResult:
    """Steps 5-7 on sets already built (``build_sets``): consensus, selection, pose estimate.
    ``timings`` and ``started`` carry the earlier stages' timings into the result."""
    started = time.perf_counter() if started is None else started
    timings = {} if timings is None else timings
    params, n_cav = sets.params, len(sets.cav_xy)
    t = time.perf_counter()
    chosen = select(sets.candidates, sets.voted_by, sets.rule, sets.ego_xy, sets.cav_xy, params.distance_limit)
    timings["consensus_selection"] = time.perf_counter() - t

    t = time.perf_counter()
    pairs = chosen.pairs
    src, dst = sets.cav_xy[pairs[:, 1]], sets.ego_xy[pairs[:, 0]]
    estimated = len(pairs) >= 2
    correction = robust_se2(src, dst, params.welsch_floor) if estimated else np.eye(3)
    timings["estimate"] = time.perf_counter() - t
    timings["total"] = time.perf_counter() - started

    anchor = None if chosen.anchor is None else (chosen.anchor // n_cav, chosen.anchor % n_cav)
    return MatchResult(
        pairs=pairs.astype(np.intp),
        transform=correction @ init,
        init=init,
        estimated=estimated,
        anchor=anchor,
        candidate_count=chosen.candidate_count,
        consensus_count=len(pairs),
        runner_up_count=chosen.runner_up_count,
        residuals=residuals(correction, src, dst),
        timings=timings,
    )
