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
TITLE_AT = -12.0
"""x (metres behind the ego) of a copy's title."""
PANEL_PX = 388
"""CSS pixels the control panel, docked at the page's right (``app.server``), takes from a page's
width: viser's ``large`` width (24 em of its 16 px font) and the dock's 4 px seam. The scene's canvas
is the rest."""
SCREEN = (math.radians(50.0), 1280 - PANEL_PX, 720)
"""(vertical field of view, width, height) of the canvas assumed before the browser reports its
camera: a 1280x720 window's part left of the control panel."""
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


def over_layout(position: tuple[float, float, float], look_at: tuple[float, float, float], centre_y: float,
                screen: tuple[float, int, int] = SCREEN) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The default top-down camera (``position``, ``look_at``) moved sideways onto the layout's
    centre ``centre_y`` and raised so that two copies side by side fit the canvas (the copies are
    ``2 |centre_y|`` apart, each about as wide)."""
    x, _, z = position
    if centre_y:
        z = max(z, fitting_height(4.0 * abs(centre_y), screen))
    return (x, centre_y, z), (look_at[0], centre_y, 0.0)


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
    """(vertical field of view, width, height) of a viser camera's canvas, ``SCREEN`` until the
    browser reports it. Width and height are the drawing buffer's pixels: CSS pixels times the
    screen's pixel ratio (2 on most laptops' screens, and lowered by viser when frames come
    slowly), so only their ratio is read as a length on the page."""
    return (camera.fov, camera.image_width, camera.image_height) if camera.update_timestamp else SCREEN


def looking_down(focus: tuple[float, float], height: float, tilt: float) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """A camera ``height`` metres above ``focus`` looking at it, standing ``tilt`` metres behind it
    per metre of height (a camera looking straight down has no 'up' to keep x pointing up the
    screen)."""
    x, y = focus
    return (x - tilt * height, y, height), (x, y, 0.0)


def fitting_height(span: float, screen: tuple[float, int, int] = SCREEN, margin: float = 1.25) -> float:
    """Height of a camera looking straight down at which ``span`` metres across (screen x) fill the
    canvas, with ``margin`` to spare: the canvas shows ``2 z tan(fov / 2) width / height`` metres
    across at height z."""
    fov, width, height = screen
    return margin * span / (2.0 * math.tan(fov / 2.0) * width / height)
