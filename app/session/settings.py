"""Everything one browser tab has chosen, as one immutable value, and its preset form.

A preset is the TOML form of ``Settings`` without the frame and the CAV: a table per part, keys
named like the fields of ``evaluation.scenario.ScenarioParams``, ``cbm.CBMParams``, the method
parameter classes and ``cbm.TrackingParams`` (angles in degrees, as everywhere at the edges).
``evaluation.presets`` reads the method, scenario and tracking tables, for the app and ``evaluate.py
--preset`` alike; the app adds ``[view]``.
The defaults are the shipped ``default`` preset's (``evaluation.presets.default_preset``).
"""
from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

from cbm import CBMParams, TrackingParams
from cbm.methods import METHODS
from evaluation.presets import PresetParams, default_preset, preset_params, replaced
from evaluation.scenario import ScenarioParams
from evaluation.trials import AUTO_CAV

Layout = Literal["overlay", "after", "before", "side by side"]
LAYOUTS: tuple[str, ...] = ("overlay", "after", "before", "side by side")
LinePairs = Literal["refined", "own"]
MAX_CAVS = 4
"""The most CAVs a tab shows at once (each in its own colour, ``app.scene.colours.CAV_COLOURS``)."""
LINE_PAIRS = {"refined": "all pairs (after refinement)", "own": "CBM's own pairs"}
"""What the match lines show for CBM: the final pairs, or CBM's own before the guided re-association."""


@dataclass(frozen=True)
class ViewOptions:
    """What the 3D view shows."""

    layout: Layout = "overlay"
    """CAV boxes ``before`` calibration (at ``init``), ``after`` (at the estimate), both overlaid, or
    the two scenes side by side (before on the left)."""
    ghosts: bool = False
    """Ground-truth outlines of every object either agent sees."""
    lines: bool = True
    """Match lines: right (green), wrong (red), missed true pairs (grey, dashed); presentation mode
    draws them in the Okabe-Ito palette and tells them apart by dash and width too."""
    line_pairs: LinePairs = "refined"
    """CBM's lines: its final pairs (``refined``) or its own pairs before the re-association (``own``)."""
    labels: bool = True
    """A label on the object clicked last."""
    pinned_lines: bool = True
    """The pinned baseline's match lines, faint grey (only while a baseline is pinned)."""
    presentation: bool = False
    """Presentation mode: a colour-blind-safe palette, large labels, the key numbers in the 3D view,
    the camera over the two agents and the control panel collapsed."""
    dark: bool = False
    """The dark theme (this tab only)."""
    points: bool = False
    """The two agents' LiDAR points, when the dataset ships them (OPV2V ``.pcd``)."""
    points_every: int = 10
    """Subsampling of the LiDAR points: every ``points_every``-th point is drawn."""
    follow: bool = True
    """The camera frames every frame shown (the agents and the pairs that explain it), unless a person
    moved it; off: it stays still."""
    sight: bool = False
    """Each agent's sight (range protocol): the area its sensor sees, a translucent fill in its colour,
    with the shadows behind the boxes under line of sight (``app.session.seen``)."""
    fused: bool = False
    """Late fusion (``evaluation.fusion``): outlines of the fused boxes, green a true positive, red a false
    one (BEV IoU 0.7 against what either agent sees), at each panel's CAV pose."""

    def __post_init__(self) -> None:
        if self.layout not in LAYOUTS:
            raise ValueError(f"ViewOptions.layout must be one of {LAYOUTS}, got {self.layout!r}")
        if self.line_pairs not in LINE_PAIRS:
            raise ValueError(f"ViewOptions.line_pairs must be one of {tuple(LINE_PAIRS)}, got {self.line_pairs!r}")
        if isinstance(self.points_every, bool) or not isinstance(self.points_every, int) or self.points_every < 1:
            raise ValueError(f"ViewOptions.points_every must be an integer >= 1, got {self.points_every!r}")


DEFAULT_SCENARIO = default_preset().scenario
"""The shipped default preset's: the range protocol (the recording car is the ego, another vehicle
the CAV) with the paper's SIND localization offset and mild detection noise: a wrong pose anyone can
see, repaired by CBM."""


def default_method_params() -> dict[str, Any]:
    """The shipped default preset's parameters of every method by its parameter set (methods that
    share one appear once)."""
    return dict(default_preset().params)


@dataclass(frozen=True)
class Settings:
    """One tab's choices: frame, agents, scenario, method and its parameters, view."""

    frame: int = 0
    cav: str = AUTO_CAV
    """The vehicle acting as the CAV, or ``auto`` (the one nearest 25 m from the ego)."""
    cavs: int = 1
    """How many CAVs (1 to ``MAX_CAVS``): the first is ``cav``, the others the vehicles next nearest
    25 m from the ego (``evaluation.trials.frame_cav_inputs``), each calibrated to the ego."""
    method: str = "cbm"
    scenario: ScenarioParams = DEFAULT_SCENARIO
    method_params: Mapping[str, Any] = field(default_factory=default_method_params)
    """Parameters of every method by ``Method.params_key`` (the CBM methods share one set)."""
    tracking: TrackingParams = default_preset().tracking
    """How CBM over time (``cbm-time``) follows the CAV's pose error from frame to frame."""
    view: ViewOptions = ViewOptions()

    @property
    def cbm(self) -> CBMParams:
        return self.method_params["cbm"]

    @property
    def params(self) -> Any:
        """The parameters of the selected method (as set; ``Method.resolved`` adds what it forces)."""
        return self.method_params[METHODS[self.method].params_key]

    def with_scenario(self, **changes: Any) -> Settings:
        """These settings with some scenario parameters changed."""
        return dataclasses.replace(self, scenario=dataclasses.replace(self.scenario, **changes))

    def with_view(self, **changes: Any) -> Settings:
        """These settings with some view options changed."""
        return dataclasses.replace(self, view=dataclasses.replace(self.view, **changes))

    def with_tracking(self, **changes: Any) -> Settings:
        """These settings with some tracking parameters changed."""
        return dataclasses.replace(self, tracking=dataclasses.replace(self.tracking, **changes))

    def with_params(self, method: str, **changes: Any) -> Settings:
        """These settings with some parameters of ``method`` changed."""
        key = METHODS[method].params_key
        params = dict(self.method_params)
        params[key] = dataclasses.replace(params[key], **changes)
        return dataclasses.replace(self, method_params=params)


def to_preset(settings: Settings) -> dict[str, Any]:
    """The TOML-ready form of ``settings`` (frame, CAV and CAV count left out: they belong to the dataset)."""
    params = {name: dataclasses.asdict(p) for name, p in settings.method_params.items() if dataclasses.fields(p)}
    return {"method": settings.method, "scenario": dataclasses.asdict(settings.scenario),
            "view": dataclasses.asdict(settings.view), **params, "tracking": dataclasses.asdict(settings.tracking)}


def from_preset(data: Mapping[str, Any], base: Settings | None = None) -> Settings:
    """Settings from a preset's tables; missing keys keep ``base``'s values. Raises ``KeyError``
    naming an unknown table or key, ``TypeError``/``ValueError`` naming a field of the wrong type."""
    base = base or Settings()
    read = preset_params(data, PresetParams(base.method, base.scenario, base.method_params, base.tracking))
    return Settings(frame=base.frame, cav=base.cav, cavs=base.cavs, method=read.method, scenario=read.scenario,
                    method_params=read.params, tracking=read.tracking,
                    view=replaced("view", base.view, data.get("view", {})))
