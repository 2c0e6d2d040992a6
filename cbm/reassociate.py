"""Guided re-association after CBM (beyond the paper, step 7b).

CBM's answer is one anchor's set (eq. 14): under hard noise its local tests (eq. 8) miss many true
pairs, although once the pose is known most true pairs lie within a metre or two of each other.
So, starting from CBM's pairs and pose estimate:

1. move the CAV boxes by the estimate and pair all boxes one-to-one by a gated assignment
   (``cbm.engine.assignment.gated_assignment``: global nearest neighbour, scipy's
   ``linear_sum_assignment``) whose cost reads the centre distance in units of the pairs' noise
   sigma, the heading axes and the sizes;
2. refit the pose on the new pairs (``cbm.estimate``; the noise sigma is re-read from them);
3. repeat until the pairs stop changing, at most ``MAX_ROUNDS`` times.

Guard against drift: the refined answer replaces CBM's only when it holds at least as many pairs
(``Refinement.accepted``); otherwise CBM's stands.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from . import se2
from .engine.assignment import gated_assignment
from .engine.threads import check_stop
from .result import Fit

MAX_ROUNDS = 5
"""Most association / refit rounds (the pairs usually stop changing after two or three)."""

Refit = Callable[[np.ndarray, np.ndarray], Fit]
"""Fit of (src, dst) centres, ``dst ~ T src``: ``cbm.estimate.robust_fit`` or ``least_squares_fit``."""


@dataclass(frozen=True)
class Refinement:
    """The pairs and pose after re-association, and whether they replaced CBM's."""

    pairs: np.ndarray
    """(K, 2) (ego index, CAV index), one-to-one, sorted by ego index."""
    fit: Fit
    """Fit of the correction on ``pairs`` (CAV boxes already moved by ``init``)."""
    rounds: int
    """Association rounds run."""
    accepted: bool
    """False when the refined pairs were fewer than CBM's; then ``pairs`` and ``fit`` are CBM's."""


def reassociate(ego: np.ndarray, cav: np.ndarray, pairs: np.ndarray, fit: Fit, gate: float,
                refit: Refit) -> Refinement:
    """Re-associate ``ego`` and ``cav`` boxes (the CAV's moved by ``init``) starting from CBM's
    ``pairs`` and their ``fit``; the gate is ``gate`` times the current fit's noise sigma."""
    current, current_fit, rounds = pairs, fit, 0
    while rounds < MAX_ROUNDS:
        rounds += 1
        check_stop()
        moved = se2.apply_boxes(current_fit.transform, cav)
        found = gated_assignment(ego, moved, gate * current_fit.sigma, current_fit.sigma)
        if len(found) < 2 or np.array_equal(found, current):
            break
        current, current_fit = found, refit(cav[found[:, 1], :2], ego[found[:, 0], :2])
    if len(current) < len(pairs):
        return Refinement(pairs, fit, rounds, accepted=False)
    return Refinement(current, current_fit, rounds, accepted=True)
