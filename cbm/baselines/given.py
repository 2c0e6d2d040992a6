"""Two methods that take what they are given instead of matching: ``none`` reports the prior pose
as it is (no calibration), ``oracle`` fits the true pairs, which only a simulation knows, by least
squares. They frame every table: ``none`` is what calibration starts from, ``oracle`` what a plain
fit of perfect matches gives (a robust fit or the pose graph can do better on the same pairs)."""
from __future__ import annotations

from dataclasses import dataclass
from time import perf_counter

import numpy as np

from ..estimate import weighted_procrustes
from ..inputs import checked_boxes, checked_transform
from ..result import MatchResult
from ._common import check_params, make_result, sort_pairs


@dataclass(frozen=True)
class NoParams:
    """``none`` and ``oracle`` have no parameters."""


def match_none(ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray,
               params: NoParams | None = None) -> MatchResult:
    """No calibration: the initial, wrong pose is the answer and nothing is matched. Its RRE and
    RTE are those of the localization (``estimated`` is True: the pose it reports is ``init``)."""
    check_params(params, NoParams)
    checked_boxes("ego_boxes", ego_boxes)
    checked_boxes("cav_boxes", cav_boxes)
    init = checked_transform("init", init)
    return MatchResult(pairs=np.zeros((0, 2), dtype=np.intp), transform=init.copy(), init=init.copy(),
                       estimated=True, anchor=None, candidate_count=0, consensus_count=0, runner_up_count=0,
                       residuals=np.zeros(0), timings={"total": 0.0})


def match_oracle(ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray,
                 params: NoParams | None = None, *, true_pairs: np.ndarray) -> MatchResult:
    """The true pairs, fitted by least squares (eq. 15 with psi(r) = r^2): the pose error left is
    the detection noise's alone. Fewer than 2 true pairs: no estimate (``init`` stays)."""
    check_params(params, NoParams)
    ego_boxes = checked_boxes("ego_boxes", ego_boxes)
    cav_boxes = checked_boxes("cav_boxes", cav_boxes)
    init = checked_transform("init", init)
    pairs = sort_pairs(true_pairs)
    if len(pairs) and (pairs.min() < 0 or pairs[:, 0].max() >= len(ego_boxes) or pairs[:, 1].max() >= len(cav_boxes)):
        raise ValueError(f"true_pairs must index the boxes ({len(ego_boxes)} ego, {len(cav_boxes)} CAV)")
    started = perf_counter()
    transform = (weighted_procrustes(cav_boxes[pairs[:, 1], :2], ego_boxes[pairs[:, 0], :2])
                 if len(pairs) >= 2 else init)
    return make_result(ego_boxes, cav_boxes, pairs, transform, init, {"total": perf_counter() - started})
