"""The context inspector as a newcomer reads it (issue 24, item 9): ids that do not overprint,
plates that hide the map under the panels, every colour in the legend, counts in the singular."""
from __future__ import annotations

import dataclasses
import itertools

import numpy as np

from app.scene import drawing, inspector
from app.scene.colours import CAV_BOXES, EGO_BOXES
from app.scene.linecolours import as_shown
from app.session.explorer import Explorer
from app.session.settings import Settings


def _inspected(explorer: Explorer, dark: bool = False):
    settings = Settings().with_scenario(protocol="sind", sigma_p=0.3, sigma_theta=3.0).with_view(dark=dark)
    outcome = explorer.compute(settings)
    picture = drawing.draw(outcome, {})
    return outcome, inspector.inspect(outcome, picture, *map(int, outcome.result.anchor))


def test_neighbour_ids_do_not_overprint_as_the_look_at_camera_shows_them(small_explorer: Explorer) -> None:
    _, shown = _inspected(small_explorer)
    scale = inspector.looked_at_scale(shown.span)
    for agent in ("ego", "cav"):
        tips = [(text, np.array(at[:2])) for name, (text, at) in shown.labels.items()
                if name.startswith(f"inspector_{agent}_tip")]
        assert len(tips) >= 3
        boxes = [inspector.label_box(at, text, scale) for text, at in tips]
        assert not any(inspector._overlap(a, b) for a, b in itertools.combinations(boxes, 2))


def test_the_panels_stand_on_plates_that_hide_the_map(small_explorer: Explorer) -> None:
    _, shown = _inspected(small_explorer)
    plate = shown.drawing().meshes["inspector_plates"]
    assert len(plate.faces) == 4 and plate.color == inspector.PLATES[False]
    lines = np.concatenate([line.segments for line in shown.lines.values() if len(line.segments)])
    assert (lines[..., 2] > inspector.PLATE_HEIGHT).all() and (plate.vertices[:, 2] > 0).all()
    low, high = plate.vertices[:, :2].min(axis=0), plate.vertices[:, :2].max(axis=0)
    assert (lines[..., :2] >= low - 1e-3).all() and (lines[..., :2] <= high + 1e-3).all()
    _, dark = _inspected(small_explorer, dark=True)
    assert dark.drawing().meshes["inspector_plates"].color == inspector.PLATES[True]
    assert len(inspector.empty().meshes["inspector_plates"].faces) == 0


def test_the_legend_names_every_colour_and_the_lines_show_it(small_explorer: Explorer) -> None:
    outcome, shown = _inspected(small_explorer)
    legend = shown.labels["inspector_legend"][0]
    for word in ("blue", "orange", "grey", "purple", "green", "red"):
        assert word in legend
    drawn = shown.drawing().lines
    assert drawn["inspector_ego_vectors"].color == as_shown(EGO_BOXES)
    assert drawn["inspector_cav_vectors"].color == as_shown(CAV_BOXES)
    assert "Blue: the ego object's context vectors" in shown.markdown


def test_one_pair_is_one_pair(small_explorer: Explorer) -> None:
    outcome, shown = _inspected(small_explorer)
    assert " 1 pairs" not in shown.markdown
    result = dataclasses.replace(outcome.result, consensus_count=1)
    assert "with 1 pair." in inspector._markdown(dataclasses.replace(outcome, result=result), *map(
        int, outcome.result.anchor), outcome.cbm().explanation.anchor(*map(int, outcome.result.anchor)),
        outcome.cbm().explanation.params)
