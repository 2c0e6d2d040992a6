"""What CBM knows before it picks an anchor: steps 1-3 of the paper's section III (the CAV boxes in
the ego frame by eq. 5, the headings, the context vectors of eq. 6-7) and the local matching of
eq. 8-9 (every candidate set L_ij), with the voting sets the consensus reads (sigma3, as in the
authors' released code: beyond the paper), built by the engine (``cbm.engine``) once per input.
``cbm.match`` selects from them; ``cbm.Explanation`` explains any anchor from them."""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .engine import CandidateSets, PairSets, Reuse, candidate_sets, local_matching
from .engine.context import Prepared, prepare
from .engine.threads import check_stop, stop_flag
from .params import CBMParams


@dataclass(frozen=True)
class Sets:
    """Everything CBM knows before it picks an anchor (steps 1-4 and the sets of step 5)."""

    params: CBMParams
    ego_boxes: np.ndarray
    """(Ne, 7) ego boxes."""
    prepared: Prepared
    """Steps 1-3 of this input (``cbm.engine.context.prepare``)."""
    candidates: CandidateSets
    """L_ij of every anchor (eq. 9) by pair id ``i * Nc + j``: sizes, and members on demand."""
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
    """Steps 1-3, then card(L_ij) of every anchor (eq. 8-9) and the voting sets (sigma3) grouped by
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
