"""What a panel may ask of its browser tab, and how a control reports a person's edit."""
from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

import viser

from ..scene.drawing import Drawing
from ..session.explorer import Explorer, Outcome
from ..session.markup import no_html
from ..session.offers import Offers
from ..session.recording import Recording
from ..session.settings import Settings

Edit = Callable[[Settings], Settings]


class TabActions(Protocol):
    """The browser tab, as its panels see it (``app.tab.ClientSession`` implements it)."""

    client: viser.ClientHandle
    explorer: Explorer
    recording: Recording
    """The frames shown under the current settings (for the shareable recording)."""
    offers: Offers
    """What the dataset cannot offer, and why."""

    @property
    def settings(self) -> Settings: ...

    def current(self) -> tuple[Outcome | None, Drawing | None]:
        """The outcome on screen and its drawing (None before the first frame)."""

    def apply(self, edit: Edit, *, move_controls: bool = False, frame_camera: bool = False) -> None:
        """Replace the settings by ``edit(settings)`` and recompute; ``move_controls`` when the
        change did not come from the controls (a preset, a jump, a search result); ``frame_camera``
        when the camera is to frame the result (a jump to a frame)."""

    def step(self, delta: int) -> None: ...

    def set_playing(self, playing: bool) -> None: ...

    def reset_camera(self, oblique: bool = False) -> None: ...

    def hide_click_label(self) -> None:
        """Hide the label of the object clicked last."""

    def add_frames(self, settings: Settings, rows: list[dict]) -> None:
        """A sequence run's rows (``evaluation.sweep``'s) join the timeline, if ``settings`` are the current ones."""

    def notify(self, title: str, body: str, color: str) -> None: ...


def on_user(handle: Any, react: Callable[[], None]) -> None:
    """Call ``react()`` when a person edits ``handle`` in the browser. viser also calls update
    callbacks when the app itself assigns a value (with no client): those are ignored, so moving
    the controls to new settings never fires a second change."""
    handle.on_update(lambda event: react() if event.client is not None else None)


def assign(handle: Any, **values: Any) -> None:
    """Give ``handle`` each of ``values`` it does not hold already. viser sends nothing for a value
    equal to the one held either, but only after casting it by its type hints: a tenth of a
    millisecond each, and a tab's controls are re-shown on every edit. A markdown panel's content
    is given with no HTML (``no_html``): viser would render it as is."""
    for name, value in values.items():
        if name == "content" and isinstance(handle, viser.GuiMarkdownHandle):
            value = no_html(value)
        if getattr(handle, name) != value:
            setattr(handle, name, value)
