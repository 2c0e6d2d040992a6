"""The Scenario tab: protocol, localization error, detection noise, co-visibility, line of sight,
late messages (delay and jitter), clutter (missed detections, false boxes), a detector's score
threshold, seed. A control the protocol does not read (or the dataset gives nothing to) is
disabled, a localization the dataset cannot give is not offered, and the tab's note says why."""
from __future__ import annotations

from dataclasses import dataclass, field

import viser

from evaluation.scenario import RANGES

from ..scene.words import SCENARIO_WORDS
from ..session.offers import Offers
from ..session.settings import Settings
from .actions import TabActions, assign, on_user
from .registry import Panel


def shown(name: str) -> tuple[float, float]:
    """A slider's ends: the field's one range (``evaluation.scenario.RANGES``), from 0 (a negative
    offset is a preset's or the command line's)."""
    low, high = RANGES[name]
    return max(low, 0.0), high


SLIDERS = {
    # field: (label, min, max, step, hint)
    "eta": (SCENARIO_WORDS["eta"], *shown("eta"), 0.05, "SIND protocol: share of objects both agents see"),
    "sigma_p": (SCENARIO_WORDS["sigma_p"], *shown("sigma_p"), 0.05, "detection position noise, std-dev on x and y"),
    "sigma_theta": (SCENARIO_WORDS["sigma_theta"], *shown("sigma_theta"), 0.5, "detection heading noise, std-dev"),
    "flip_prob": (SCENARIO_WORDS["flip_prob"], *shown("flip_prob"), 0.05, "probability a detection faces backwards"),
    "loc_x": (SCENARIO_WORDS["loc_x"], *shown("loc_x"), 0.25,
              "CAV pose error in x: offset (fixed) or std-dev (gaussian, drifting); none: how far off a guess of "
              "the pose may be (0: the CAV's frame is taken for the ego's)"),
    "loc_y": (SCENARIO_WORDS["loc_y"], *shown("loc_y"), 0.25, "CAV pose error in y"),
    "loc_yaw": (SCENARIO_WORDS["loc_yaw"], *shown("loc_yaw"), 0.5, "CAV pose error in yaw"),
    "loc_tau": (SCENARIO_WORDS["loc_tau"], *shown("loc_tau"), 1.0,
                "drifting: frames this many seconds apart share 1/e of "
                "the bias (GNSS: tens of seconds to minutes)"),
    "loc_white": (SCENARIO_WORDS["loc_white"], *shown("loc_white"), 0.05,
                  "drifting: noise drawn anew every frame on top of the "
                  "bias, as a share of each axis's std-dev"),
    "sensor_range": (SCENARIO_WORDS["sensor_range"], *shown("sensor_range"), 5.0,
                     "range protocol: what each agent sees"),
    "miss_rate": (SCENARIO_WORDS["miss_rate"], *shown("miss_rate"), 0.05,
                  "probability that an agent misses a detection it "
                  "would make, 0 to 1 (each agent draws its own misses)"),
    "false_rate": (SCENARIO_WORDS["false_rate"], *shown("false_rate"), 0.05,
                   "false boxes added to each agent's detections, "
                   "per real detection (0.3: 3 false boxes for 10 real ones); they match no object"),
    "min_score": (SCENARIO_WORDS["min_score"], *shown("min_score"), 0.05, "a detector's boxes (--detections) "
                        "scored below this are dropped; 0 keeps all"),
    "sight_share": (SCENARIO_WORDS["sight_share"], *shown("sight_share"), 0.05,
                    "line of sight: an agent sees an object when at least this share of its footprint, as the "
                    "sensor looks at it, is not hidden behind nearer boxes"),
    "delay_ms": (SCENARIO_WORDS["delay_ms"], *shown("delay_ms"), 10.0,
                 "the CAV's message reaches the ego this long after capture: its objects and pose are those of "
                 "that earlier time (interpolated between frames), added to the dataset's own gap between the "
                 "agents' timestamps"),
    "jitter_ms": (SCENARIO_WORDS["jitter_ms"], *shown("jitter_ms"), 10.0,
                  "each frame's delay varies uniformly within ± this (drawn from the seed); delay plus jitter "
                  "at most 1000 ms"),
}
SIGHT_HINT = ("range protocol: each agent sees an object only when enough of its footprint is in its line of sight, "
              "not hidden behind nearer boxes (where the dataset says what an agent saw, that); View > agents' sight "
              "draws what each sees")
AFTER_SIGHT = ("sight_share", "delay_ms", "jitter_ms")
"""The sliders placed after the line-of-sight checkbox, in this order."""
PROTOCOLS_READING = {"eta": ("sind",), "sensor_range": ("range", "opv2v"), "sight": ("range",),
                     "sight_share": ("range",)}
"""The protocols under which a slider acts (the others act under every protocol); opv2v reads the
sensor range in a dataset without per-agent visibility."""
LOCALIZATIONS = ("fixed", "gaussian", "drifting", "dataset", "none")
"""``drifting``: a bias that drifts over time like GNSS (``evaluation.drift``); ``dataset``: the
CAV's own reported pose where the release has one (OPV2V's ``predicted_ego_pos``); ``none``: no GNSS,
no prior (the identity, or a guess within ``loc_x`` metres with any heading)."""
SIMULATED_ERROR = ("loc_x", "loc_y", "loc_yaw")
"""The sliders of a simulated localization error (unread under ``dataset``)."""
DRIFT = ("loc_tau", "loc_white")
"""The sliders of a drifting localization error (read under ``drifting`` only)."""


@dataclass
class ScenarioControls:
    protocol: viser.GuiDropdownHandle
    localization: viser.GuiDropdownHandle
    sliders: dict[str, viser.GuiSliderHandle]
    sight: viser.GuiCheckboxHandle
    seed: viser.GuiNumberHandle
    note: viser.GuiMarkdownHandle
    offers: Offers = field(default_factory=Offers)

    def show(self, settings: Settings) -> None:
        scenario = settings.scenario
        self.protocol.value, self.localization.value = scenario.protocol, scenario.localization
        for name, slider in self.sliders.items():
            slider.value = getattr(scenario, name)
        self.sight.value = scenario.sight
        self.seed.value = scenario.seed

    def reflect(self, settings: Settings) -> None:
        """Disable the sliders the scenario does not read, with the reason in their hint and the note."""
        reasons: dict[str, list[str]] = {}
        for name, control in {**self.sliders, "sight": self.sight}.items():
            why = unread_reason(settings, name) or (self.offers.scores if name == "min_score" else None)
            hint = SIGHT_HINT if name == "sight" else SLIDERS[name][4]
            assign(control, disabled=why is not None, hint=hint if why is None else f"Disabled: {why}. {hint}")
            if why is not None:
                reasons.setdefault(why, []).append(SCENARIO_WORDS[name])
        lines = [f"*Disabled ({why}): {', '.join(names)}.*" for why, names in reasons.items()]
        if self.offers.reported_poses:
            lines.append(f"*Not offered: localization error `dataset` ({self.offers.reported_poses}).*")
        assign(self.note, content="  \n".join(lines), visible=bool(lines))


def unread_reason(settings: Settings, name: str) -> str | None:
    """Why the scenario slider ``name`` has no effect under ``settings``; None when it acts."""
    scenario = settings.scenario
    if scenario.protocol not in PROTOCOLS_READING.get(name, (scenario.protocol,)):
        return f"no effect under the {scenario.protocol} protocol"
    if name in SIMULATED_ERROR and scenario.localization == "dataset":
        return "the dataset's own localization is used"
    if name in ("loc_y", "loc_yaw") and scenario.localization == "none":
        return "no GNSS: the pose is unknown (localization x sets how far off a guess may be, 0: none)"
    if name in DRIFT and scenario.localization != "drifting":
        return "the localization error does not drift"
    if name == "sight_share" and not scenario.sight:
        return "line of sight is off"
    return None


def build(gui: viser.GuiApi, settings: Settings, offers: Offers) -> ScenarioControls:
    scenario = settings.scenario
    localizations = tuple(name for name in LOCALIZATIONS if name != "dataset" or not offers.reported_poses)
    protocol = gui.add_dropdown("protocol", ("range", "sind", "opv2v"), initial_value=scenario.protocol)
    localization = gui.add_dropdown("localization error", localizations, initial_value=scenario.localization,
                                    hint="fixed offset, gaussian draw anew each frame, drifting over time like GNSS, "
                                         "the dataset's own (the pose the CAV reported), or none: no GNSS at all, "
                                         "the CAV's pose unknown")
    sliders = {name: _slider(gui, name, settings) for name in SLIDERS if name not in AFTER_SIGHT}
    sight = gui.add_checkbox(SCENARIO_WORDS["sight"], scenario.sight, hint=SIGHT_HINT)
    sliders.update({name: _slider(gui, name, settings) for name in AFTER_SIGHT})
    return ScenarioControls(protocol=protocol, localization=localization, sliders=sliders, sight=sight,
                            seed=gui.add_number("seed", scenario.seed, min=0, step=1),
                            note=gui.add_markdown("", visible=False), offers=offers)


def _slider(gui: viser.GuiApi, name: str, settings: Settings) -> viser.GuiSliderHandle:
    """The slider of scenario field ``name`` (``SLIDERS``) at its value in ``settings``."""
    label, low, high, step, hint = SLIDERS[name]
    return gui.add_slider(label, low, high, step, getattr(settings.scenario, name), hint=hint)


def bind(c: ScenarioControls, tab: TabActions) -> None:
    on_user(c.protocol, lambda: tab.apply(lambda s: s.with_scenario(protocol=c.protocol.value)))
    on_user(c.localization, lambda: tab.apply(lambda s: s.with_scenario(localization=c.localization.value)))
    for name, slider in c.sliders.items():
        on_user(slider, lambda n=name, h=slider: tab.apply(lambda s: s.with_scenario(**{n: float(h.value)})))
    on_user(c.sight, lambda: tab.apply(lambda s: s.with_scenario(sight=bool(c.sight.value))))
    on_user(c.seed, lambda: tab.apply(lambda s: s.with_scenario(seed=max(0, int(c.seed.value)))))


PANEL = Panel("Scenario", 10, "what the agents see: protocol, detection noise, localization error, line of sight, "
              "late messages, clutter, seed",
              lambda gui, tab: build(gui, tab.settings, tab.offers), bind)
