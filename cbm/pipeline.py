"""CBM, steps 1-7 of the paper's section III, from two box lists and a wrong relative pose."""
from __future__ import annotations

import time

import numpy as np

from . import se2
from .consensus import PairSets, sets_within
from .context import build_context, fold_heading, pair_signs
from .estimate import residuals, robust_se2
from .inputs import checked_boxes, checked_transform
from .local_matching import accepted_quadruples
from .params import CBMParams
from .result import MatchResult
from .selection import select


def match(ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray | None = None,
          params: CBMParams | None = None) -> MatchResult:
    """Match ego and CAV boxes by their context and refine the CAV->ego transform.

    ``ego_boxes`` (Ne, 7) are in the ego frame, ``cav_boxes`` (Nc, 7) in the CAV frame, rows
    ``x, y, z, length, width, height, yaw``; ``init`` is the (wrong) CAV->ego transform from
    localization (identity when None).
    """
    started = time.perf_counter()
    params = CBMParams() if params is None else params
    if not isinstance(params, CBMParams):
        raise ValueError(f"params must be a CBMParams, got {type(params).__name__}")
    ego = checked_boxes("ego_boxes", ego_boxes)
    cav = checked_boxes("cav_boxes", cav_boxes)
    init = np.eye(3) if init is None else checked_transform("init", init)
    timings: dict[str, float] = {}

    def lap(stage: str, since: float) -> float:
        now = time.perf_counter()
        timings[stage] = now - since
        return now

    cav_in_ego = se2.apply_boxes(init, cav)
    ego_xy, cav_xy = ego[:, :2], cav_in_ego[:, :2]
    ego_heading, cav_heading = fold_heading(ego[:, 6]), fold_heading(cav_in_ego[:, 6])
    signs = pair_signs(ego_heading, cav_heading, params.heading)
    ego_context, cav_context = build_context(ego_xy, ego_heading), build_context(cav_xy, cav_heading)
    t = lap("context", started)

    radius = max(params.sigma2, params.sigma3) if params.consensus else params.sigma2
    quads = accepted_quadruples(ego_context, cav_context, ego_heading, cav_heading, signs, params.sigma1_rad, radius)
    t = lap("local_matching", t)

    n_pairs = len(ego) * len(cav)
    rule = params.consensus_rule if params.consensus else None
    candidates = sets_within(quads, params.sigma2, n_pairs)
    voted_by = sets_within(quads, params.sigma3, n_pairs, by_member=True) if rule else PairSets.empty(n_pairs)
    t = lap("candidate_sets", t)

    chosen = select(candidates, voted_by, rule, ego_xy, cav_xy, params.distance_limit)
    t = lap("consensus_selection", t)

    pairs = chosen.pairs
    src, dst = cav_xy[pairs[:, 1]], ego_xy[pairs[:, 0]]
    estimated = len(pairs) >= 2
    correction = robust_se2(src, dst, params.welsch_floor) if estimated else np.eye(3)
    lap("estimate", t)
    timings["total"] = time.perf_counter() - started

    anchor = None if chosen.anchor is None else (chosen.anchor // len(cav), chosen.anchor % len(cav))
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
