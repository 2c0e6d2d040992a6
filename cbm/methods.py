"""Every calibration method, one record each: the app's method list and panels, the evaluation's
``--methods``, sweeps and search all read this registry. Adding a method is one module (its run
function and parameter class) and one entry in ``METHODS``.

    from cbm.methods import METHODS, run
    result = run("vips", ego_boxes, cav_boxes, init, labels=(ego_labels, cav_labels))
"""
from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .baselines import (
    FreeAlignParams,
    ICPParams,
    NoParams,
    RICPParams,
    V2XRegParams,
    VIPSParams,
    match_freealign,
    match_icp,
    match_none,
    match_oracle,
    match_ricp,
    match_v2xregpp,
    match_vips,
)
from .params import CBMParams
from .pipeline import match
from .posegraph import match_graph
from .prior_free import PRIOR_FREE, match_without_prior
from .result import MatchResult
from .sequence import SequenceCalibrator, Smoother, match_first_step
from .track import TrackingParams


@dataclass(frozen=True)
class Method:
    """One method: how it is named and shown, its parameters, how it runs and what it can explain."""

    name: str
    """Key used on the command line, in tables and in presets."""
    label: str
    """Name shown to people (the app's method list)."""
    params: type
    """Its parameter dataclass; ``params()`` are the defaults."""
    function: Callable[..., MatchResult]
    """``function(ego_boxes, cav_boxes, init, params, **inputs) -> MatchResult``."""
    forced: Mapping[str, Any] = field(default_factory=dict)
    """Parameters it always runs with, whatever is asked (the ablation: consensus off)."""
    shares: str | None = None
    """Another method whose parameter set it uses in the app (one set of CBM thresholds for both)."""
    takes_labels: bool = False
    """Needs the objects' class labels (``ego_labels=``, ``cav_labels=``)."""
    takes_truth: bool = False
    """Needs the true pairs (``true_pairs=``): only a simulation can run it."""
    explains: bool = False
    """Builds CBM's sets: consensus margin, diagnosis, context inspector and CBM's own pairs apply."""
    requires: Mapping[str, tuple[str, Any]] = field(default_factory=dict)
    """Parameters that matter only while another has a value: ``{"sigma3": ("consensus", True)}``."""
    takes_peers: bool = False
    """Uses the frame's other CAV trials (``peers=``, more than two agents): the joint pose graph."""
    over_time: bool = False
    """Calibrates a sequence frame after frame (``calibrator``): its frames run in time order, per
    CAV; called on one frame alone it is that frame's first step."""
    offline: bool = False
    """Over time, and answers only once every frame is in (``cbm.sequence.Smoother``: the frames after a frame
    count too): a whole recording's method, for runs over every frame."""

    @property
    def params_key(self) -> str:
        """The name under which the app keeps this method's parameter set."""
        return self.shares or self.name

    @property
    def tunable(self) -> tuple[str, ...]:
        """The parameters a user or a grid may set (its GUI controls): every field not forced."""
        return tuple(f.name for f in dataclasses.fields(self.params) if f.name not in self.forced)

    def controls(self, params: Any) -> tuple[str, ...]:
        """The parameters that act under ``params`` (as it runs them): the GUI shows these only."""
        resolved = self.resolved(params)

        def acts(name: str) -> bool:
            needed, value = self.requires.get(name, (None, None))
            return needed is None or getattr(resolved, needed) == value

        return tuple(name for name in self.tunable if acts(name))

    def resolved(self, params: Any = None) -> Any:
        """``params`` (or the defaults) with the forced parameters applied: what it runs with."""
        params = self.params() if params is None else params
        if not isinstance(params, self.params):
            raise TypeError(f"params of {self.name} must be {self.params.__name__}, got {type(params).__name__}")
        return dataclasses.replace(params, **self.forced) if self.forced else params

    def calibrator(self, params: Any = None, tracking: TrackingParams | None = None) -> SequenceCalibrator | Smoother:
        """A fresh calibrator over time with ``params`` and ``tracking`` (``over_time`` methods only);
        an offline method's is a ``cbm.sequence.Smoother``, whose ``smoothed()`` answers at the end."""
        if not self.over_time:
            raise ValueError(f"{self.name} calibrates every frame alone; it has no calibrator over time")
        return (Smoother if self.offline else SequenceCalibrator)(self.resolved(params), tracking)

    def __call__(self, ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray, params: Any = None, *,
                 labels: tuple[np.ndarray, np.ndarray] | None = None,
                 true_pairs: np.ndarray | None = None, peers: Sequence[Any] = ()) -> MatchResult:
        """Run on one trial's boxes; ``labels`` (ego, CAV), ``true_pairs`` and ``peers`` (the
        frame's other CAV trials) reach the methods that take them (the oracle cannot run without
        ``true_pairs``)."""
        inputs: dict[str, Any] = {"peers": peers} if self.takes_peers else {}
        if self.takes_labels and labels is not None:
            inputs.update(ego_labels=labels[0], cav_labels=labels[1])
        if self.takes_truth:
            if true_pairs is None:
                raise ValueError(f"{self.name} needs true_pairs: it fits the true pairs")
            inputs["true_pairs"] = true_pairs
        return self.function(ego_boxes, cav_boxes, init, self.resolved(params), **inputs)


ORACLE_WORDS = "least squares on the true pairs"
"""What the oracle is: a reference that knows the true pairs, not a bound (a robust fit of the same
pairs, or a pose graph over more agents, can come closer to the true pose)."""

CBM_REQUIRES = {"sigma3": ("consensus", True), "consensus_rule": ("consensus", True), "refine_gate": ("refine", True)}
"""CBM's parameters that act only with the consensus or the re-association on."""

METHODS: dict[str, Method] = {m.name: m for m in (
    Method("none", "none (no calibration)", NoParams, match_none),
    Method("cbm", "CBM", CBMParams, match, explains=True, requires=CBM_REQUIRES),
    Method("cbm-no-consensus", "CBM without consensus", CBMParams, match, forced={"consensus": False},
           shares="cbm", explains=True, requires=CBM_REQUIRES),
    Method("cbm-graph", "CBM + pose graph (3+ agents)", CBMParams, match_graph, shares="cbm",
           requires=CBM_REQUIRES, takes_peers=True),
    Method("cbm-time", "CBM over time", CBMParams, match_first_step, shares="cbm", requires=CBM_REQUIRES,
           over_time=True),
    Method("cbm-smooth", "CBM over a whole recording (smoothed)", CBMParams, match_first_step, shares="cbm",
           requires=CBM_REQUIRES, over_time=True, offline=True),
    Method("cbm-no-prior", "CBM without a prior", CBMParams, match_without_prior, forced=PRIOR_FREE, shares="cbm",
           requires=CBM_REQUIRES),
    Method("icp", "ICP", ICPParams, match_icp),
    Method("ricp", "RICP", RICPParams, match_ricp),
    Method("vips", "VIPS", VIPSParams, match_vips, takes_labels=True),
    Method("v2xregpp", "V2X-Reg++", V2XRegParams, match_v2xregpp, takes_labels=True),
    Method("freealign", "FreeAlign", FreeAlignParams, match_freealign),
    Method("oracle", f"oracle ({ORACLE_WORDS})", NoParams, match_oracle, takes_truth=True),
)}
"""The methods in the order tables and lists show them: the references bound the others."""


def method(name: str) -> Method:
    """The method ``name``; ``ValueError`` naming the choices for an unknown one."""
    if name not in METHODS:
        raise ValueError(f"method must be one of {', '.join(METHODS)}, got {name!r}")
    return METHODS[name]


def run(name: str, ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray, params: Any = None,
        **inputs: Any) -> MatchResult:
    """Run the method ``name`` (``labels=``, ``true_pairs=`` as it needs them)."""
    return method(name)(ego_boxes, cav_boxes, init, params, **inputs)
