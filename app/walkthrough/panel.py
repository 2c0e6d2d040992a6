"""The Walkthrough tab of the control panel: CBM's nine steps on the frame on screen, one at a time,
with prev / next, an animation where motion explains, and a way back to the normal scene. It
follows the tab's recomputes: a new outcome redraws the current step."""
from __future__ import annotations

import threading
import time

import viser

from ..panels.actions import TabActions
from ..session.explorer import Outcome
from . import steps
from .facts import Facts, gather
from .nodes import WalkthroughNodes, glide

FRAMES = 20
"""Poses of one animation."""
SECONDS = 1.5
"""Length of one animation."""
PANEL_SHIFT = 0.15
"""Sideways shift of the look-at point per metre of height, so the object clears the control panel."""
LOOK_HEIGHT = 45.0
"""Metres above the followed object of the camera that looks at it."""
TAB = "Steps"
"""The tab's name: short, so that the panel's six tabs fit on one row at its width (384 px)."""
IDLE = "Walk through CBM's steps on the frame on screen: **start** (or next step ▶) shows step 1 in the scene."


class WalkthroughPanel:
    """The controls of the Walkthrough tab and the state of the walkthrough of one browser tab."""

    def __init__(self, gui: viser.GuiApi, tabs: viser.GuiTabGroupHandle, tab: TabActions) -> None:
        self.tab = tab
        self.nodes = WalkthroughNodes(tab.client)
        self.index = 0
        self.active = False
        self.step: steps.Step | None = None
        self._facts: Facts | None = None
        self._lock = threading.RLock()
        self._generation = 0
        """Bumped by every redraw: an animation of an older step stops."""
        with tabs.add_tab(TAB):
            self.title = gui.add_markdown(f"**{steps.title(0)}**")
            self.text = gui.add_markdown(IDLE)
            self.start = gui.add_button("start walkthrough", hint="show CBM's steps on this frame in the scene")
            self.prev = gui.add_button("◀ prev step")
            self.next = gui.add_button("next step ▶")
            self.play = gui.add_button("play animation", visible=False,
                                       hint="the CAV's boxes glide from the wrong pose to the estimate")
            self.look = gui.add_button("look at the object", visible=False, hint="the camera over the followed object")
            self.leave = gui.add_button("leave walkthrough", color="red", visible=False)
        self.start.on_click(lambda e: self.go(self.index))
        self.prev.on_click(lambda e: self.go(self.index - 1 if self.active else self.index))
        self.next.on_click(lambda e: self.go(self.index + 1 if self.active else self.index))
        self.play.on_click(lambda e: threading.Thread(target=self.animate, daemon=True).start())
        self.leave.on_click(lambda e: self.exit())
        self.look.on_click(lambda e: self.look_at_object())

    def go(self, index: int) -> None:
        """Show step ``index`` (clamped to the nine) of the outcome on screen."""
        outcome, _ = self.tab.current()
        if outcome is None:
            self.tab.notify("Nothing to walk through", "wait for the first frame to be computed", "yellow")
            return
        with self._lock:
            self.index = min(max(index, 0), len(steps.BUILDERS) - 1)
            self.active = True
            self._draw(outcome)

    def refresh(self, outcome: Outcome) -> None:
        """Follow a recompute: the current step is redrawn for the new outcome."""
        with self._lock:
            if self.active:
                self._draw(outcome)

    def exit(self) -> None:
        """Leave the walkthrough: its nodes hidden, the normal scene shown again."""
        with self._lock:
            self._generation += 1
            self.active, self.step, self._facts = False, None, None
            self.nodes.hide()
            self.text.content = IDLE
            self._buttons()

    def look_at_object(self) -> None:
        """Point the camera down on the followed object, left of the control panel (reset camera goes back)."""
        if self.step is None or self.step.focus is None:
            return
        x, y = self.step.focus
        camera = self.tab.client.camera
        y -= PANEL_SHIFT * LOOK_HEIGHT
        camera.position, camera.look_at = (x - 8.0, y, LOOK_HEIGHT), (x, y, 0.0)

    def animate(self) -> None:
        """Glide the CAV's boxes along the step's motion in ``FRAMES`` pose updates over ``SECONDS``
        (a newer redraw or another animation stops it)."""
        with self._lock:
            if not self.active or self.step is None or self.step.motion is None:
                return
            self._generation += 1
            generation, step = self._generation, self.step
        for pose in glide(*step.motion, FRAMES):
            with self._lock:
                if generation != self._generation:
                    return
                self.nodes.place(pose)
            time.sleep(SECONDS / FRAMES)

    def _draw(self, outcome: Outcome) -> None:
        if self._facts is None or self._facts.outcome is not outcome:
            self._facts = gather(outcome)
        self._generation += 1
        self.step = steps.build(self._facts, self.index)
        self.nodes.show(self.step)
        self.title.content = f"**{self.step.title}**"
        self.text.content = self.step.text
        self._buttons()

    def _buttons(self) -> None:
        self.start.visible, self.leave.visible = not self.active, self.active
        self.play.visible = self.active and self.step is not None and self.step.motion is not None
        self.look.visible = self.active and self.step is not None and self.step.focus is not None
        self.prev.disabled = self.active and self.index == 0
        self.next.disabled = self.active and self.index == len(steps.BUILDERS) - 1
