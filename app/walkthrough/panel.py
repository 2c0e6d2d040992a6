"""The walkthrough (the Steps tab of the control panel): CBM's nine steps on the frame on screen, one
at a time, with prev / next, an animation where motion explains (its length can be set), and a way
back to the normal scene. Stepping to a step about the followed pair puts the camera over it, close
enough to read what the step draws; the other steps show the whole scene; leaving puts back the
camera the walkthrough started from. It follows the tab's recomputes: a new outcome redraws the
current step (the camera stays)."""
from __future__ import annotations

import threading
import time

import viser

from ..panels.actions import TabActions, assign
from ..scene import layouts
from ..session.explorer import Outcome
from . import steps
from .facts import Facts, gather
from .nodes import WalkthroughNodes, glide

FRAMES_PER_SECOND = 15
"""Poses an animation sends per second."""
SECONDS = 1.5
"""Length of an animation unless set otherwise."""
TILT = 0.05
"""How far behind the object the camera that looks at it stands, per metre of height (x stays up)."""
IDLE_TITLE = "**CBM in nine steps**"
IDLE = "Walk through CBM's steps on the frame on screen: **start** (or next step ▶) shows step 1 in the scene."


class WalkthroughPanel:
    """The controls of the Walkthrough tab and the state of the walkthrough of one browser tab."""

    def __init__(self, gui: viser.GuiApi, tab: TabActions) -> None:
        self.tab = tab
        self.nodes = WalkthroughNodes(tab.client)
        self.index = 0
        self.active = False
        self.step: steps.Step | None = None
        self._facts: Facts | None = None
        self._lock = threading.RLock()
        self._generation = 0
        """Bumped by every redraw: an animation of an older step stops."""
        self._camera: tuple[tuple[float, ...], tuple[float, ...]] | None = None
        """Where the camera stood when the walkthrough started."""
        self.title = gui.add_markdown(IDLE_TITLE)
        self.text = gui.add_markdown(IDLE)
        self.start = gui.add_button("start walkthrough", hint="show CBM's steps on this frame in the scene")
        self.prev = gui.add_button("◀ prev step")
        self.next = gui.add_button("next step ▶")
        self.play = gui.add_button("play animation", visible=False,
                                   hint="the CAV's boxes glide from the wrong pose to the estimate")
        self.seconds = gui.add_slider("animation (s)", 0.5, 8.0, 0.5, SECONDS, visible=False,
                                      hint="how long the animation takes: slower for a lecture hall")
        self.look = gui.add_button("look at the object", visible=False, hint="the camera over the followed object")
        self.leave = gui.add_button("leave walkthrough", color="red", visible=False)
        self.start.on_click(lambda e: self.go(self.index))
        self.prev.on_click(lambda e: self.go(self.index - 1 if self.active else self.index))
        self.next.on_click(lambda e: self.go(self.index + 1 if self.active else self.index))
        self.play.on_click(lambda e: threading.Thread(target=self.animate, daemon=True).start())
        self.leave.on_click(lambda e: self.exit())
        self.look.on_click(lambda e: self.look_at_object())

    def go(self, index: int) -> None:
        """Show step ``index`` (clamped to the nine) of the outcome on screen, the camera over the
        followed object in the steps about it and over the scene in the others."""
        outcome, _ = self.tab.current()
        if outcome is None:
            self.tab.notify("Nothing to walk through", "wait for the first frame to be computed", "yellow")
            return
        with self._lock:
            if not self.active:
                camera = self.tab.client.camera
                self._camera = (tuple(camera.position), tuple(camera.look_at))
            if self._facts is None or self._facts.outcome is not outcome:
                self._facts = gather(outcome)
            self.index = min(max(index, 0), steps.count(self._facts) - 1)
            self.active = True
            self._draw(outcome)
            if self.step.focus is not None:
                self.look_at_object()
            else:
                self.tab.reset_camera()
                self.nodes.view.lay_out()

    def refresh(self, outcome: Outcome, _picture: object) -> None:
        """Follow a recompute: the current step is redrawn for the new outcome (the step draws its own picture)."""
        with self._lock:
            if self.active:
                self._draw(outcome)

    def exit(self) -> None:
        """Leave the walkthrough: its nodes hidden, the normal scene, the tab's title and the camera
        the walkthrough started from shown again."""
        with self._lock:
            self._generation += 1
            self.active, self.step, self._facts = False, None, None
            self.nodes.hide()
            assign(self.title, content=IDLE_TITLE)
            assign(self.text, content=IDLE)
            self._buttons()
            if self._camera is not None:
                layouts.move_camera(self.tab.client, *self._camera)
                self._camera = None

    def look_at_object(self) -> None:
        """Point the camera down on the followed object, left of the control panel, high enough to
        show what the step draws about it (``Step.span``; reset camera goes back); the step's labels
        spread apart for that camera."""
        if self.step is None or self.step.focus is None:
            return
        client = self.tab.client
        layouts.move_camera(client, *camera_over(self.step.focus, self.step.span, layouts.screen_of(client.camera)))
        self.nodes.view.lay_out()

    def animate(self) -> None:
        """Glide the CAV's boxes along the step's motion over the seconds the slider sets
        (``FRAMES_PER_SECOND`` pose updates a second; a newer redraw or another animation stops it)."""
        with self._lock:
            if not self.active or self.step is None or self.step.motion is None:
                return
            self._generation += 1
            generation, step = self._generation, self.step
        seconds = float(self.seconds.value)
        frames = max(2, round(seconds * FRAMES_PER_SECOND))
        for pose in glide(*step.motion, frames):
            with self._lock:
                if generation != self._generation:
                    return
                self.nodes.place(pose)
            time.sleep(seconds / frames)

    def _draw(self, outcome: Outcome) -> None:
        if self._facts is None or self._facts.outcome is not outcome:
            self._facts = gather(outcome)
        self._generation += 1
        self.index = min(self.index, steps.count(self._facts) - 1)
        self.step = steps.build(self._facts, self.index)
        self.nodes.show(self.step)
        assign(self.title, content=f"**{self.step.title}**")
        assign(self.text, content=self.step.text)
        self._buttons()

    def _buttons(self) -> None:
        self.start.visible, self.leave.visible = not self.active, self.active
        moves = self.active and self.step is not None and self.step.motion is not None
        self.play.visible = self.seconds.visible = moves
        self.look.visible = self.active and self.step is not None and self.step.focus is not None
        self.prev.disabled = self.active and self.index == 0
        last = steps.count(self._facts) - 1 if self._facts is not None else len(steps.BUILDERS) - 1
        self.next.disabled = self.active and self.index >= last


def camera_over(focus: tuple[float, float], span: float,
                screen: tuple[float, int, int]) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """A camera looking down on ``focus`` from the height at which ``span`` metres fit the canvas."""
    return layouts.looking_down(focus, layouts.fitting_height(span, screen), TILT)
