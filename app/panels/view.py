"""The View tab: layout, ghosts, match lines (and, for CBM, its own pairs or all), labels, the agents'
sight (disabled, with the reason, unless the range protocol decides what each agent sees), camera,
presentation mode and the dark theme, and the legend of the palette in use. LiDAR points are
disabled, with the reason, on a dataset without point clouds; their subsampling also while they are off."""
from __future__ import annotations

from dataclasses import dataclass, field

import viser

from cbm.methods import METHODS

from ..scene.cavs import legend as cavs_legend
from ..scene.colours import palette
from ..session.offers import Offers
from ..session.settings import LAYOUTS, LINE_PAIRS, Settings
from .actions import TabActions, assign, on_user
from .registry import Panel

TOGGLES = ("ghosts", "lines", "labels", "presentation", "dark", "pinned_lines", "points", "fused", "follow", "sight")
"""The view options a checkbox of the same name sets."""
LINE_PAIR_KEYS = {label: key for key, label in LINE_PAIRS.items()}
POINTS_HINT = "The ego's and the CAV's LiDAR points (datasets with .pcd files), the CAV's placed like its boxes"
EVERY_HINT = "Draw every Nth LiDAR point (1: all of them)"
POINTS_OFF = "LiDAR points are off: tick LiDAR points to draw them"
SIGHT_HINT = ("What the ego and the CAV see, a translucent fill in each one's colour: within the sensor range, and "
              "with Scenario > line of sight on, the shadows behind the boxes (an object in the CAV's shadow is "
              "not co-visible)")


def sight_unread(settings: Settings) -> str | None:
    """Why the agents' sight is not drawn under ``settings`` (None: it is)."""
    protocol = settings.scenario.protocol
    return None if protocol == "range" else f"the {protocol} protocol does not decide by geometry what each agent sees"


def points_note(unavailable: str | None, idle: str | None) -> str:
    """The note under the points' controls: why they are greyed out (empty when they are not)."""
    if unavailable is not None:
        return f"*Disabled ({unavailable}): LiDAR points, points: every Nth.*"
    return f"*Disabled ({idle}): points: every Nth.*" if idle else ""


@dataclass
class ViewControls:
    layout: viser.GuiDropdownHandle
    ghosts: viser.GuiCheckboxHandle
    lines: viser.GuiCheckboxHandle
    line_pairs: viser.GuiDropdownHandle
    labels: viser.GuiCheckboxHandle
    pinned_lines: viser.GuiCheckboxHandle
    reset_camera: viser.GuiButtonHandle
    view_3d: viser.GuiButtonHandle
    follow: viser.GuiCheckboxHandle
    presentation: viser.GuiCheckboxHandle
    dark: viser.GuiCheckboxHandle
    points: viser.GuiCheckboxHandle
    points_every: viser.GuiSliderHandle
    legend: viser.GuiMarkdownHandle
    fused: viser.GuiCheckboxHandle
    sight: viser.GuiCheckboxHandle
    note: viser.GuiMarkdownHandle
    """Why the LiDAR points or their subsampling are disabled (hidden when they are not)."""
    offers: Offers = field(default_factory=Offers)

    def show(self, settings: Settings) -> None:
        view = settings.view
        self.layout.value, self.line_pairs.value = view.layout, LINE_PAIRS[view.line_pairs]
        for name in TOGGLES:
            getattr(self, name).value = getattr(view, name)
        self.points_every.value = view.points_every

    def reflect(self, settings: Settings) -> None:
        assign(self.line_pairs, visible=METHODS[settings.method].explains)
        why = self.offers.points
        assign(self.points, disabled=why is not None,
               hint=POINTS_HINT if why is None else f"Disabled: {why}. {POINTS_HINT}")
        idle = why or (None if settings.view.points else POINTS_OFF)
        assign(self.points_every, disabled=idle is not None,
               hint=EVERY_HINT if idle is None else f"Disabled: {idle}. {EVERY_HINT}")
        assign(self.note, content=points_note(why, idle), visible=idle is not None)
        assign(self.legend, content=palette(settings.view).legend + cavs_legend(settings.cavs))
        unread = sight_unread(settings)
        assign(self.sight, disabled=unread is not None,
               hint=SIGHT_HINT if unread is None else f"Disabled: {unread}. {SIGHT_HINT}")


def build(gui: viser.GuiApi, settings: Settings, offers: Offers) -> ViewControls:
    view = settings.view
    controls = ViewControls(
        layout=gui.add_dropdown("CAV boxes", LAYOUTS, initial_value=view.layout),
        ghosts=gui.add_checkbox("ground-truth ghosts", view.ghosts),
        lines=gui.add_checkbox("match lines", view.lines),
        line_pairs=gui.add_dropdown("CBM's lines", tuple(LINE_PAIRS.values()),
                                    initial_value=LINE_PAIRS[view.line_pairs],
                                    hint="CBM's own pairs (eq. 14), or all pairs after the guided re-association"),
        labels=gui.add_checkbox("label clicked objects", view.labels),
        sight=gui.add_checkbox("agents' sight", view.sight, hint=SIGHT_HINT),
        pinned_lines=gui.add_checkbox("show pinned matches", view.pinned_lines,
                                      hint="The pinned baseline's match lines, thin violet (pin under the timeline)"),
        reset_camera=gui.add_button("reset camera", hint="Straight down on the scene, framing the agents and the "
                                                          "pairs that explain the frame: footprints show as compared"),
        view_3d=gui.add_button("3D view", hint="From behind and above the ego (reset camera: back to top-down)"),
        follow=gui.add_checkbox("camera follows", view.follow,
                                hint="Frame every frame shown, the agents and the pairs that explain it (off: the "
                                     "camera stays still; a camera you moved stays until reset camera)"),
        presentation=gui.add_checkbox("presentation mode", view.presentation,
                                      hint="Colour-blind-safe palette, large labels, the key numbers in the 3D "
                                           "view, the camera over the two agents, this panel minimised"),
        dark=gui.add_checkbox("dark theme", view.dark, hint="A dark page and scene, in this browser tab only"),
        points=gui.add_checkbox("LiDAR points", view.points, hint=POINTS_HINT),
        points_every=gui.add_slider("points: every Nth", 1, 50, 1, view.points_every,
                                    hint=EVERY_HINT),
        note=gui.add_markdown("", visible=False),
        legend=gui.add_markdown(palette(view).legend + cavs_legend(settings.cavs)),
        fused=gui.add_checkbox("fused boxes (late fusion)", view.fused,
                               hint="The ego's and the CAV's boxes merged by NMS at this pose: outlines green for "
                                    "a true positive, red for a false one (BEV IoU 0.7 against the ground truth)"),
        offers=offers)
    return controls


def bind(c: ViewControls, tab: TabActions) -> None:
    for name, control in (("layout", c.layout), *((n, getattr(c, n)) for n in TOGGLES)):
        on_user(control, lambda n=name, h=control: tab.apply(lambda s: s.with_view(**{n: h.value})))
    on_user(c.line_pairs, lambda: tab.apply(lambda s: s.with_view(line_pairs=LINE_PAIR_KEYS[c.line_pairs.value])))
    c.reset_camera.on_click(lambda e: tab.reset_camera())
    c.view_3d.on_click(lambda e: tab.reset_camera(oblique=True))
    on_user(c.points_every, lambda: tab.apply(lambda s: s.with_view(points_every=int(c.points_every.value))))


PANEL = Panel("View", 30, "what the 3D view draws: layout, match lines, labels, camera, presentation mode, legend",
              lambda gui, tab: build(gui, tab.settings, tab.offers), bind)
