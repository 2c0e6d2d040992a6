"""The pinned run drawn beside the current one: a copy of the scene of its own (the ego's boxes, the
CAV's at the pinned method's estimate, both vehicles, its pairs right, wrong and missed in the
palette's strokes), to the left of everything the current drawing holds, each copy titled with its
method. Two methods' pairs on one frame side by side; ``pinned`` draws them over each other instead."""
from __future__ import annotations

import dataclasses

import numpy as np

from cbm import se2
from cbm.methods import METHODS

from ..session.explorer import Outcome
from . import colours, geometry, pairs, planes
from .drawing import Drawing, Lines, Mesh, no_lines
from .layouts import SIDE_GAP, TITLE_AT

STROKES = ("right", "wrong", "missed")
MARKS = {"wrong_marks": ("wrong", 3.0), "missed_marks": ("missed", 2.0)}
"""The pinned copy's marks of wrong and missed pairs: the colour of the pairs' stroke, the thickness."""
MESHES = ("pinned_ego_boxes", "pinned_cav_boxes", "pinned_ego_vehicle", "pinned_cav_vehicle")
LINES = (*(f"pinned_{s}" for s in STROKES), *(f"pinned_{m}" for m in MARKS))


def title(outcome: Outcome, role: str) -> str:
    """A copy's title: its method and its role (current, pinned)."""
    return f"{METHODS[outcome.settings.method].label.split(' (')[0]} ({role})"


def offset_beside(picture: Drawing, outcome: Outcome, pinned: Outcome) -> float:
    """Metres sideways (+y, the screen's left) at which the pinned copy clears everything ``picture``
    draws by ``SIDE_GAP``."""
    drawn = [boxes[:, :2] for boxes, _ in picture.objects.values()] + [np.array(picture.agents).reshape(-1, 2)]
    left = float(np.concatenate(drawn)[:, 1].max()) if drawn else 0.0
    own = np.concatenate([pinned.trial.ego_boxes[:, :2],
                          se2.apply_points(pinned.result.transform, pinned.trial.cav_boxes[:, :2]), np.zeros((1, 2))])
    return left - float(own[:, 1].min()) + SIDE_GAP


def empty() -> tuple[dict[str, Mesh], dict[str, Lines]]:
    """The pinned copy's nodes, empty (hidden)."""
    meshes = {name: Mesh(np.zeros((0, 3), np.float32), np.zeros((0, 3), np.uint32), (0, 0, 0)) for name in MESHES}
    return meshes, {name: Lines(no_lines(), (0, 0, 0)) for name in LINES}


def with_pinned_beside(picture: Drawing, outcome: Outcome, pinned: Outcome) -> Drawing:
    """``picture`` with the pinned run's copy of the scene beside it (see the module), both copies
    titled, the camera's spots and centre taking in both."""
    palette = colours.palette(outcome.settings.view)
    offset = np.array([0.0, offset_beside(picture, outcome, pinned)])
    shift = se2.make(offset[0], offset[1], 0.0)
    trial, result = pinned.trial, pinned.result
    ego = pairs.Drawn(se2.apply_boxes(shift, trial.ego_boxes), trial.ego_ids)
    cav = pairs.Drawn(se2.apply_boxes(shift @ result.transform, trial.cav_boxes), trial.cav_ids)
    shapes = pairs.pair_shapes(pinned.shown_pairs, trial.gt_pairs, ego, cav, palette, "CAV", "pinned_pairs")
    vehicles = [shift, shift @ result.transform]
    meshes = {"pinned_ego_boxes": Mesh(*geometry.footprint_mesh(ego.boxes, planes.EGO), palette.ego_boxes),
              "pinned_cav_boxes": Mesh(*geometry.footprint_mesh(cav.boxes, planes.cav(1)), palette.cav_boxes),
              "pinned_ego_vehicle": Mesh(*geometry.vehicle_mesh(vehicles[:1]), palette.ego_vehicle),
              "pinned_cav_vehicle": Mesh(*geometry.vehicle_mesh(vehicles[1:]), palette.cav_vehicle)}
    lines = {**{f"pinned_{s}": Lines(getattr(shapes, s), getattr(palette, s).color, getattr(palette, s).thickness)
                for s in STROKES},
             **{f"pinned_{m}": Lines(getattr(shapes, m), getattr(palette, stroke).color, width)
                for m, (stroke, width) in MARKS.items()}}
    titles = {"title_current": (title(outcome, "current"), (TITLE_AT, picture.centre_y, planes.LABELS)),
              "title_pinned": (title(pinned, "pinned"), (TITLE_AT, float(offset[1]), planes.LABELS))}
    agents = tuple(tuple(map(float, se2.translation_of(pose))) for pose in vehicles)
    return dataclasses.replace(picture, meshes={**picture.meshes, **meshes}, lines={**picture.lines, **lines},
                               labels={**picture.labels, **shapes.labels, **titles},
                               agents=picture.agents + agents, centre_y=(picture.centre_y + float(offset[1])) / 2)
