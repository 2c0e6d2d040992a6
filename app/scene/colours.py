"""The palettes of the scene, in RGB: the standard one, and a colour-blind-safe one (Okabe-Ito) for
presentation mode, each with a variant for the dark theme."""
from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass

from ..session.settings import ViewOptions

RGB = tuple[int, int, int]

EGO_BOXES = (52, 120, 246)
CAV_BOXES = (255, 140, 0)
CAV_BEFORE = (255, 185, 110)
"""Outlines of the CAV's boxes where the wrong pose puts them: a faint CAV orange."""
EGO_VEHICLE = (16, 40, 150)
CAV_VEHICLE = (200, 110, 0)
RIGHT = (30, 170, 60)
WRONG = (225, 30, 30)
MISSED = (140, 140, 140)
GHOST = (110, 110, 110)
CAV_COLOURS = ((0, 160, 160), (86, 180, 233), (240, 228, 66))
"""The boxes of the second, third and fourth CAV (``Settings.cavs``): teal, Okabe-Ito sky blue and
yellow, apart from the ego's blue, the first CAV's orange and a wrong pair's red (the reddish purple
they had read as a wrong pair's red beside its red outlines). Every CAV colour of every palette, the
vehicles' included, lies at least 30 apart in CIELAB (ΔE*ab) from the palette's wrong-pair colour
(``tests/app/test_failure_picture.py``): the dark orange vehicle of old lay 25 from the red, and read
as red."""
MAP = {"lane_boundary": (185, 185, 185), "crossing": (225, 200, 120), "drivable_area": (215, 215, 215)}
MAP_OTHER = (200, 200, 200)


@dataclass(frozen=True)
class Stroke:
    """How one kind of match line is drawn."""

    color: RGB
    thickness: float
    """Screen pixels."""
    dash: float | None = None
    """Length of the dashes (and of the gaps between them) in metres; None: a solid line."""


@dataclass(frozen=True)
class Palette:
    """Every colour of the scene and the strokes of the match lines, with the legend that names them."""

    ego_boxes: RGB
    cav_boxes: RGB
    cav_before: RGB
    ego_vehicle: RGB
    cav_vehicle: RGB
    right: Stroke
    wrong: Stroke
    missed: Stroke
    ghost: RGB
    map: Mapping[str, RGB]
    map_other: RGB
    legend: str
    """Markdown for the View tab."""


LABELS_NOTE = ", each pair labelled with its ids"
CROSSED_NOTE = (" A box crossed out in grey (with the ground-truth ghosts): a false box, a detection of no object"
                " (the scenario's false boxes).")
"""The legends' words on the crosses over false boxes."""
"""The legends' words on the pair labels (the HTML recording, which draws no labels, leaves them out)."""

STANDARD = Palette(
    EGO_BOXES, CAV_BOXES, CAV_BEFORE, EGO_VEHICLE, CAV_VEHICLE,
    right=Stroke(RIGHT, 3.0), wrong=Stroke(WRONG, 3.0), missed=Stroke(MISSED, 2.0, 0.8),
    ghost=GHOST, map=MAP, map_other=MAP_OTHER,
    legend="Boxes: **ego** blue, **CAV** orange (faint: before calibration). Lines: green right pair, red wrong "
           "pair, grey dashed a true pair missed; the boxes of a wrong pair are outlined red, of a missed one grey"
           + LABELS_NOTE + "." + CROSSED_NOTE)

OKABE_ITO = Palette(
    ego_boxes=(0, 114, 178), cav_boxes=(230, 159, 0), cav_before=(240, 205, 130),
    ego_vehicle=(0, 70, 120), cav_vehicle=(150, 110, 0),
    right=Stroke((0, 158, 115), 3.0), wrong=Stroke((213, 94, 0), 6.0, 0.8), missed=Stroke((150, 150, 150), 1.5, 0.2),
    ghost=GHOST, map=MAP, map_other=MAP_OTHER,
    legend="Colour-blind-safe palette (Okabe-Ito). Boxes: **ego** blue, **CAV** orange (faint: before "
           "calibration). Lines: **right** pair bluish green, solid; **wrong** pair vermillion, thick and dashed; "
           "a true pair **missed** thin grey dots; the boxes of a wrong pair are outlined vermillion, of a missed "
           "one grey" + LABELS_NOTE + "." + CROSSED_NOTE)

DARK_SCENE = {"ghost": (90, 90, 90), "cav_before": (150, 100, 40), "map_other": (46, 46, 52),
              "map": {"lane_boundary": (52, 52, 58), "crossing": (75, 62, 30), "drivable_area": (40, 40, 46)}}
"""What the dark theme changes: outlines and map lines dim colours that show on the dark background
without outshining the boxes and match lines (viser brightens line colours: they are taken as linear)."""
DARK_VEHICLES = {STANDARD.ego_vehicle: ((110, 150, 255), (255, 160, 40)),
                 OKABE_ITO.ego_vehicle: ((86, 180, 233), (240, 190, 80))}
"""The vehicles' dark bodies, lost on the dark background, in lighter colours (Okabe-Ito: sky blue and
a light orange), by the palette's ego vehicle colour."""


def palette(view: ViewOptions) -> Palette:
    """The palette of ``view``: Okabe-Ito in presentation mode, else the standard one; dimmer
    outlines and map lines and lighter vehicles on the dark theme."""
    chosen = OKABE_ITO if view.presentation else STANDARD
    if not view.dark:
        return chosen
    ego_vehicle, cav_vehicle = DARK_VEHICLES[chosen.ego_vehicle]
    return dataclasses.replace(chosen, ego_vehicle=ego_vehicle, cav_vehicle=cav_vehicle, **DARK_SCENE)

