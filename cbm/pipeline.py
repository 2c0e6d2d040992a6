"""CBM, steps 1-7 of the paper's section III, from two box lists and a wrong relative pose, and the
hypotheses verified beyond it (steps 7b-7c, ``cbm.hypotheses``).

Steps 1-3 (``cbm.context.prepare``), then eq. 7-13 by the engine (``cbm.engine``: the same answer as
``cbm.reference``, fast), the pose estimate (eq. 14-15, ``cbm.estimate``) and the verification.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from .context import Prepared, prepare
from .engine import (
    CandidateSets,
    PairSets,
    Reuse,
    Selection,
    Visit,
    candidate_sets,
    local_matching,
    runner_up_beside,
    select,
)
from .engine.threads import check_stop, stop_flag
from .estimate import WELSCH_EFFICIENT_SCALE, Fit, least_squares_fit, residuals, robust_fit
from .hypotheses import MIN_SHARED, Verdict, verify
from .inputs import checked_boxes, checked_transform
from .params import CBMParams
from .result import MatchResult


@dataclass(frozen=True)
class Sets:
    """Everything CBM knows before it picks an anchor (steps 1-4 and the sets of step 5)."""

    params: CBMParams
    ego_boxes: np.ndarray
    """(Ne, 7) ego boxes."""
    prepared: Prepared
    """Steps 1-3 of this input (``cbm.context.prepare``)."""
    candidates: CandidateSets
    """L_ij of every anchor (eq. 8) by pair id ``i * Nc + j``: sizes, and members on demand."""
    voted_by: PairSets
    """Row m: the pairs whose voting set holds pair m (empty when consensus is off)."""

    @property
    def cav_boxes(self) -> np.ndarray:
        """(Nc, 7) CAV boxes pre-transformed into the ego frame by ``init`` (step 1)."""
        return self.prepared.cav_boxes

    @property
    def ego_heading(self) -> np.ndarray:
        """(Ne,) folded ego headings (step 2)."""
        return self.prepared.ego_heading

    @property
    def cav_heading(self) -> np.ndarray:
        """(Nc,) folded CAV headings after ``init`` (step 2)."""
        return self.prepared.cav_heading

    @property
    def signs(self) -> np.ndarray:
        """(Ne, Nc) +1 or -1: how the CAV frame is turned against each ego frame (step 2)."""
        return self.prepared.signs

    @property
    def ego_xy(self) -> np.ndarray:
        """(Ne, 2) ego centres."""
        return self.ego_boxes[:, :2]

    @property
    def cav_xy(self) -> np.ndarray:
        """(Nc, 2) CAV centres in the ego frame after ``init``."""
        return self.cav_boxes[:, :2]

    @property
    def rule(self) -> str | None:
        return self.params.consensus_rule if self.params.consensus else None


def build_sets(ego: np.ndarray, cav: np.ndarray, init: np.ndarray, params: CBMParams,
               timings: dict[str, float] | None = None, reuse: Reuse | None = None) -> Sets:
    """Steps 1-3, then card(L_ij) of every anchor (eq. 7-8) and the voting sets (eq. 9) grouped by
    member, for checked inputs (timed together as ``local_matching``). With ``reuse``, what an
    earlier call on the same input built and no threshold changes is taken from its
    ``cbm.engine.EditCache``, which runs only what the edit changed."""
    timings = {} if timings is None else timings
    started = time.perf_counter()
    cache = None if reuse is None else reuse.cache(ego, cav, init, params.heading)
    ready = prepare(ego, cav, init, params.heading, stop_flag()) if cache is None else cache.prepared
    t = time.perf_counter()
    timings["context"] = t - started
    check_stop()

    sigma1, sigma3 = params.sigma1_rad, params.sigma3 if params.consensus else None
    if cache is None:
        count2, voted_by = local_matching(ready, sigma1, params.sigma2, sigma3)
        candidates = candidate_sets(ready, sigma1, params.sigma2, count2)
    else:
        count2, voted_by = cache.local_matching(sigma1, params.sigma2, sigma3)
        candidates = cache.candidate_sets(sigma1, params.sigma2, count2)
    timings["local_matching"] = time.perf_counter() - t
    check_stop()
    return Sets(params, ego, ready, candidates, voted_by)


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
    """Steps 5-7b on sets already built (``build_sets``): consensus, selection, pose estimate,
    guided re-association. ``timings`` and ``started`` carry the earlier stages' timings into the result."""
    return match_sets_visited(sets, init, timings, started)[0]


def match_sets_visited(sets: Sets, init: np.ndarray, timings: dict[str, float] | None = None,
                       started: float | None = None) -> tuple[MatchResult, Visit | None]:
    """``match_sets``, and what the selection's visit filtered (``cbm.engine.Visit``; None when every
    set is empty): the filtered sizes it computed, for ``cbm.inspect`` to reuse. The runner-up search
    may run beside the verification of the winner (``cbm.engine.runner_up_beside``): their time is
    then the verification's."""
    started = time.perf_counter() if started is None else started
    timings = {} if timings is None else timings
    params, n_cav = sets.params, len(sets.cav_xy)
    t = time.perf_counter()
    chosen = select(sets.candidates, sets.voted_by, sets.rule, sets.ego_xy, sets.cav_xy, params.distance_limit)
    timings["consensus_selection"] = time.perf_counter() - t
    check_stop()

    t = time.perf_counter()
    context_pairs = chosen.pairs.astype(np.intp)
    estimated = len(context_pairs) >= 2
    fit = estimate(sets.cav_xy[context_pairs[:, 1]], sets.ego_xy[context_pairs[:, 0]], params) if estimated else None
    timings["estimate"] = time.perf_counter() - t

    t = time.perf_counter()
    runner_up_count, verdict = runner_up_beside(chosen.rival, lambda: verified(sets, chosen, fit))
    spent = time.perf_counter() - t
    if verdict is None:
        timings["consensus_selection"] += spent
    else:
        timings["reassociate"] = spent
    pairs, correction = (verdict.best.pairs, verdict.best.correction) if verdict is not None else (
        context_pairs, fit.transform if estimated else np.eye(3))
    timings["total"] = time.perf_counter() - started

    return MatchResult(
        pairs=pairs,
        transform=correction @ init,
        init=init,
        estimated=estimated,
        anchor=None if chosen.anchor is None else (chosen.anchor // n_cav, chosen.anchor % n_cav),
        candidate_count=chosen.candidate_count,
        consensus_count=len(context_pairs),
        runner_up_count=runner_up_count,
        residuals=residuals(correction, sets.cav_xy[pairs[:, 1]], sets.ego_xy[pairs[:, 0]]),
        timings=timings,
        context_pairs=context_pairs,
        **verdict_fields(verdict, len(pairs), n_cav, init),
    ), chosen.visit


def verified(sets: Sets, chosen: Selection, fit: Fit | None) -> Verdict | None:
    """Steps 7b-7c on the eq. 13 winner and its robust ``fit`` (``cbm.hypotheses.verify``); None
    without a fit or with the re-association off (the paper's method)."""
    if fit is None or not sets.params.refine:
        return None
    params = sets.params
    return verify(sets, chosen.anchor, fit, lambda src, dst: estimate(src, dst, params),
                  params.welsch_floor / WELSCH_EFFICIENT_SCALE, params.refine_gate, chosen.visit)


def verdict_fields(verdict: Verdict | None, n_pairs: int, n_cav: int, init: np.ndarray) -> dict[str, Any]:
    """The result's evidence fields (step 7c): whether CBM abstains and why, the answer's and the
    runner-up's evidence, the runner-up's transform, how many hypotheses were verified and the
    answer's anchor. Without a verdict (no re-association, or fewer than 2 pairs) only the count of
    pairs can make it abstain."""
    if verdict is None:
        reason = f"fewer than {MIN_SHARED} objects could be paired" if n_pairs < MIN_SHARED else ""
        return dict(abstained=bool(reason), reason=reason)
    best, rival = verdict.best, verdict.runner_up
    return dict(abstained=bool(verdict.reason), reason=verdict.reason, evidence=best.score,
                runner_up_evidence=-math.inf if rival is None else rival.score, hypotheses=verdict.tried,
                runner_up_transform=None if rival is None else rival.correction @ init,
                answer_anchor=(best.anchor // n_cav, best.anchor % n_cav))


def estimate(src: np.ndarray, dst: np.ndarray, params: CBMParams) -> Fit:
    """Step 7 (eq. 14): the correction fitted to matched centres by the chosen estimator."""
    if params.estimator == "least_squares":
        return least_squares_fit(src, dst, params.welsch_floor)
    return robust_fit(src, dst, params.welsch_floor)
