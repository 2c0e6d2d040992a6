"""The layouts of the scene, one record each: which copies of the scene are drawn (the CAV's boxes
where ``init`` puts them, or where the estimate does), where, and with which titles. The names are
``ViewOptions.layout``'s (``app.session.settings.LAYOUTS``)."""
from __future__ import annotations

import math
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from cbm import se2

from ..session.explorer import Outcome

SIDE_GAP = 20.0
"""Metres between the two copies of the side-by-side layout."""
TITLE_AT = (-12.0, 3.0)
"""(x, height) of a copy's title."""
PANEL_PX = 384 + 2 * 16
"""CSS pixels the control panel takes from the right of the page: viser's ``large`` width (24 em)
and its margins."""
SCREEN = (math.radians(50.0), 1280, 720)
"""(vertical field of view, width, height) assumed before the browser reports its camera."""
ASIDE = (0.0, 0.0, 0.05)
"""Metres a camera move first steps aside (``move_camera``)."""
MOVING = threading.Lock()
"""Held while a camera move sets its steps: two moves at once (a button's and another callback's,
each on a thread of its own) never interleave into a pose neither asked for."""


@dataclass(frozen=True)
class Panel:
    """One copy of the scene."""

    placement: str
    """``before``: the CAV's boxes where ``init`` puts them; ``after``: where the estimate does."""
    offset: np.ndarray
    """(2,) metres added to every position of this copy."""
    title: str | None = None


@dataclass(frozen=True)
class Layout:
    name: str
    panels: Callable[[Outcome], list[Panel]]
    before_ghosts: bool = False
    """Also draw the CAV's boxes faintly where ``init`` put them."""


def single(placement: str) -> Callable[[Outcome], list[Panel]]:
    """One copy with the CAV's boxes at ``placement``."""
    return lambda outcome: [Panel(placement, np.zeros(2))]


def side_by_side(outcome: Outcome) -> list[Panel]:
    """Before on the left, after on the right, far enough apart that the boxes drawn (the ego's, and
    the CAV's where ``init`` and where the estimate put them) do not overlap."""
    trial, result = outcome.trial, outcome.result
    cav = [se2.apply_points(transform, trial.cav_boxes[:, :2]) for transform in (result.init, result.transform)]
    boxes = np.concatenate([trial.ego_boxes[:, :2], *cav, np.zeros((1, 2))])
    width = float(boxes[:, 1].max() - boxes[:, 1].min()) + SIDE_GAP
    return [Panel("before", np.array([0.0, width]), "BEFORE (CAV at init)"),
            Panel("after", np.zeros(2), "AFTER (CAV at estimate)")]


LAYOUTS: dict[str, Layout] = {layout.name: layout for layout in (
    Layout("overlay", single("after"), before_ghosts=True),
    Layout("after", single("after")),
    Layout("before", single("before")),
    Layout("side by side", side_by_side),
)}


def clear_of_panel(position: tuple[float, float, float], look_at: tuple[float, float, float], centre_y: float,
                   screen: tuple[float, int, int] = SCREEN) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The default top-down camera (``position``, ``look_at``) for the layout centred on ``centre_y``,
    shown in the part of the page left of the control panel: raised so that two copies side by side
    fit in that part (the copies are ``2 |centre_y|`` apart, each about as wide), then
    ``slid_clear_of_panel``."""
    x, _, z = position
    if centre_y:
        z = max(z, fitting_height(4.0 * abs(centre_y), screen))
    return slid_clear_of_panel((x, centre_y, z), (look_at[0], centre_y, 0.0), screen)


def move_camera(client: Any, position: Sequence[float], look_at: Sequence[float]) -> None:
    """Put the browser's camera of viser ``client`` at ``position``, looking at ``look_at``.

    viser sends a move only where it differs from its copy of the camera, and that copy is what the
    browser last reported, which may predate the previous move (its report still in flight): a
    move back to where the camera was before would then be dropped. So the move first steps
    ``ASIDE`` and back, the steps sent in one batch (the browser draws only the last), one move at
    a time (``MOVING``)."""
    camera = client.camera
    with MOVING, client.atomic():
        camera.position = np.add(position, ASIDE)
        camera.position = position
        camera.look_at = look_at


def screen_of(camera: Any) -> tuple[float, int, int]:
    """(vertical field of view, width, height) of a viser camera, ``SCREEN`` until the browser reports it."""
    return (camera.fov, camera.image_width, camera.image_height) if camera.update_timestamp else SCREEN


def free_width(width: int) -> float:
    """CSS pixels of the page left of the control panel."""
    return max(width - PANEL_PX, width / 3)


def slid_clear_of_panel(position: tuple[float, float, float], look_at: tuple[float, float, float],
                        screen: tuple[float, int, int] = SCREEN) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """A top-down camera slid sideways (to -y, the screen's right) so that what it looked at shows in
    the middle of the page's part left of the control panel: by half the panel's width, in metres at
    the look-at distance (from the vertical field of view ``screen[0]`` and the page's height)."""
    fov, width, height = screen
    metres_per_px = 2.0 * math.dist(position, look_at) * math.tan(fov / 2.0) / height
    shift = metres_per_px * (width - free_width(width)) / 2.0
    return ((position[0], position[1] - shift, position[2]), (look_at[0], look_at[1] - shift, look_at[2]))


def fitting_height(span: float, screen: tuple[float, int, int] = SCREEN, margin: float = 1.25) -> float:
    """Height of a camera looking straight down at which ``span`` metres across (screen x) fill the
    part of the page left of the control panel, with ``margin`` to spare."""
    fov, width, height = screen
    metres_per_px_per_metre = 2.0 * math.tan(fov / 2.0) / height
    return margin * span / (free_width(width) * metres_per_px_per_metre)
