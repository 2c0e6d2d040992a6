"""CBM, its ablation without global consensus, the paper's baselines (Song et al., RA-L 2024,
sec. IV): ICP, RICP and VIPS, and the references ``none`` (no calibration) and ``oracle`` (the true
pairs), each with the interface of ``cbm.match``: ``method(ego_boxes, cav_boxes, init, params=None, **kw) -> MatchResult``.

    from cbm.baselines import run
    result = run("vips", ego_boxes, cav_boxes, init, ego_labels=labels_e, cav_labels=labels_c)
"""
from __future__ import annotations

import dataclasses
from typing import Any, Callable

import numpy as np

from ..params import CBMParams
from ..pipeline import match
from ..result import MatchResult
from .icp import ICPParams, match_icp
from .reference import ReferenceParams, match_none, match_oracle
from .ricp import RICPParams, match_ricp
from .vips import VIPSParams, match_vips

Method = Callable[..., MatchResult]


def match_cbm_without_consensus(ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray,
                                params: CBMParams | None = None) -> MatchResult:
    """CBM with eq. 9-10 skipped: the paper's ablation (Table I, last column)."""
    return match(ego_boxes, cav_boxes, init, dataclasses.replace(params or CBMParams(), consensus=False))


def build_registry() -> tuple[dict[str, Method], dict[str, type]]:
    """The methods by name and their parameter classes."""
    methods: dict[str, Method] = {"none": match_none, "cbm": match, "cbm-no-consensus": match_cbm_without_consensus,
                                  "icp": match_icp, "ricp": match_ricp, "vips": match_vips, "oracle": match_oracle}
    params: dict[str, type] = {"none": ReferenceParams, "cbm": CBMParams, "cbm-no-consensus": CBMParams,
                               "icp": ICPParams, "ricp": RICPParams, "vips": VIPSParams, "oracle": ReferenceParams}
    return methods, params


METHODS, PARAMS = build_registry()
"""``METHODS[name]`` runs a method; ``PARAMS[name]()`` are its default parameters."""
TAKES_LABELS = frozenset({"vips"})
"""Methods that take the objects' class labels (``ego_labels=``, ``cav_labels=``)."""
TAKES_TRUTH = frozenset({"oracle"})
"""Methods that take the true pairs (``true_pairs=``): only a simulation can run them."""


def run(name: str, ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray, params: Any = None,
        **kw: Any) -> MatchResult:
    """Run the method ``name`` (a key of ``METHODS``); ``kw`` goes to the method (VIPS's labels, the
    oracle's true pairs)."""
    if name not in METHODS:
        raise ValueError(f"name must be one of {sorted(METHODS)}, got {name!r}")
    return METHODS[name](ego_boxes, cav_boxes, init, params, **kw)


__all__ = ["ICPParams", "METHODS", "PARAMS", "RICPParams", "ReferenceParams", "TAKES_LABELS", "TAKES_TRUTH",
           "VIPSParams", "match_cbm_without_consensus", "match_icp", "match_none", "match_oracle", "match_ricp",
           "match_vips", "run"]
