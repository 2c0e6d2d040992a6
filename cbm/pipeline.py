"""``cbm.match``: CBM, the steps of the paper's section III, from two box lists and a wrong relative
pose, and the hypotheses verified beyond it (steps 7b-7c, ``cbm.hypotheses``).

Steps 1-4 build the sets (``cbm.sets``: the CAV boxes in the ego frame, eq. 5; context, eq. 6-7;
local matching, eq. 8-9), steps 5-6 keep the global consensus and select (eq. 10-14), both by the
engine (``cbm.engine``: the same answer as ``cbm.reference``, fast); step 7 fits the pose (eq. 15-16,
``cbm.estimate``); then the verification. The one way to run CBM: the app, the evaluation and CBM
over time all call ``match``.
"""
from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from .engine import Reuse, Selection, runner_up_beside, select
from .engine.threads import check_stop, stoppable
from .estimate import WELSCH_EFFICIENT_SCALE, least_squares_fit, residuals, robust_fit
from .explain import Explanation
from .hypotheses import MIN_SHARED, Verdict, verify
from .inputs import checked_boxes, checked_transform
from .params import CBMParams
from .result import Fit, MatchResult
from .sets import Sets, build_sets


def checked_inputs(ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray | None,
                   params: CBMParams | None) -> tuple[np.ndarray, np.ndarray, np.ndarray, CBMParams]:
    """The arguments of ``match`` checked, with defaults filled in."""
    params = CBMParams() if params is None else params
    if not isinstance(params, CBMParams):
        raise ValueError(f"params must be a CBMParams, got {type(params).__name__}")
    init = np.eye(3) if init is None else checked_transform("init", init)
    return checked_boxes("ego_boxes", ego_boxes), checked_boxes("cav_boxes", cav_boxes), init, params


def match(ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray | None = None,
          params: CBMParams | None = None, *, reuse: Reuse | None = None, explain: bool = False,
          stop: Callable[[], bool] | None = None) -> MatchResult:
    """Match ego and CAV boxes by their context and refine the CAV->ego transform.

    ``ego_boxes`` (Ne, 7) are in the ego frame, ``cav_boxes`` (Nc, 7) in the CAV frame, rows
    ``x, y, z, length, width, height, yaw``; ``init`` is the (wrong) CAV->ego transform from
    localization (identity when None). Keyword options:

    - ``reuse``: a ``cbm.Reuse`` kept between calls; a call on the same boxes and ``init`` with
      other thresholds reuses what they do not change (steps 1-3, the join, the sorted blocks);
    - ``explain``: the result carries ``explanation`` (``cbm.Explanation``), the sets and fit of
      this very run, to explain any anchor;
    - ``stop``: asked while CBM runs; once it says True, ``cbm.Cancelled`` is raised (``cbm.stoppable``).
    """
    with stoppable(stop) if stop is not None else contextlib.nullcontext():
        started = time.perf_counter()
        ego, cav, init, params = checked_inputs(ego_boxes, cav_boxes, init, params)
        timings: dict[str, float] = {}
        sets = build_sets(ego, cav, init, params, timings, reuse)
        return selected_and_fitted(sets, init, timings, started, explain)


def selected_and_fitted(sets: Sets, init: np.ndarray, timings: dict[str, float], started: float,
                        explain: bool = False) -> MatchResult:
    """Steps 5-7 on the sets of steps 1-4 (``build_sets``): consensus and selection (eq. 10-14),
    the pose estimate (eq. 15-16), and beyond the paper the guided re-association and the
    verification of hypotheses (steps 7b-7c). The runner-up search may run beside the verification
    of the winner (``cbm.engine.runner_up_beside``): their time is then the verification's."""
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
        explanation=Explanation(sets, init, fit, chosen.visit) if explain else None,
        **verdict_fields(verdict, len(pairs), n_cav, init),
    )


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
    """Step 7 (eq. 15): the correction fitted to matched centres by the chosen estimator."""
    if params.estimator == "least_squares":
        return least_squares_fit(src, dst, params.welsch_floor)
    return robust_fit(src, dst, params.welsch_floor)
