"""CBM without a prior: the CAV's pose found from the boxes alone, when there is no GNSS at all.

CBM's context vectors (eq. 6-7) are each expressed in its object's own frame, so eq. 8's comparison
does not depend on the pose between the agents, and neither do the consensus (eq. 10-11) or the
selection (eq. 13). Two steps do depend on ``init``:

- the distance limit, which rejects an anchor whose pairs lie far apart under ``init``: here off;
- the heading signs (step 2). A detected heading is known up to a half turn, so headings are folded
  and each CAV frame is turned by pi where it faces away from the ego frame it is compared with.
  That turn is right for a pair when ``init`` leaves the agents' frames less than 90 degrees apart
  (less the heading noise), and only then. So CBM starts from four guesses, the agents' frames as
  they are and turned by a quarter, a half and three quarters of a turn: whatever the true rotation,
  one guess is within 45 degrees of it.

CBM runs once per guess and the answer with the most pairs wins (one that did not abstain first, the
stronger evidence on a tie). With no prior, a layout of paired objects that looks the same turned
(evenly spaced boxes on a line) cannot tell the pose: the answer abstains
(``cbm.baselines._common.unresolved``). It costs four runs of CBM; ``docs/results.md`` measures what it gives up.
"""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from . import se2
from .baselines._common import unresolved
from .params import CBMParams
from .pipeline import checked_inputs, match
from .result import MatchResult

GUESSES = (0.0, math.pi / 2, math.pi, -math.pi / 2)
"""Radians: the rotations between the agents' frames CBM is run from."""
PRIOR_FREE = {"heading": "align", "distance_limit": math.inf}
"""The parameters CBM runs with here: headings aligned per guess, no distance limit."""


def match_without_prior(ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray | None = None,
                        params: CBMParams | None = None) -> MatchResult:
    """CBM from each rotation of ``GUESSES`` with ``PRIOR_FREE`` parameters; the best answer.

    ``init`` is not used to match; it is kept as the result's starting pose (the "before" picture)
    and is the answer when neither guess gives an estimate.
    """
    ego, cav, init, params = checked_inputs(ego_boxes, cav_boxes, init, params)
    params = dataclasses.replace(params, **PRIOR_FREE)
    runs = [match(ego, cav, se2.make(0.0, 0.0, yaw), params) for yaw in GUESSES]
    best = max(runs, key=_strength)
    timings = {name: sum(r.timings.get(name, 0.0) for r in runs) for name in best.timings}
    best = dataclasses.replace(best, init=init, transform=best.transform if best.estimated else init.copy(),
                               timings=timings)
    why = unresolved(ego[best.pairs[:, 0]]) if best.estimated and not best.abstained else ""
    return dataclasses.replace(best, abstained=True, reason=why) if why else best


def _strength(result: MatchResult) -> tuple[bool, int, float]:
    """How well a run explains the scene: not abstained, then its pairs, then its evidence."""
    evidence = result.evidence if math.isfinite(result.evidence) else -math.inf
    return (result.estimated and not result.abstained, len(result.pairs), evidence)
