"""Where the camera frames what matters, and labels spread apart: the geometry, without a browser."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

import loaders
from app.scene import framing, labelling
from app.scene.camera import KEY_NUMBERS_LINE_PX, key_numbers_area
from app.scene.drawing import draw
from app.scene.framing import Area, Canvas, Spot
from app.session.explorer import Explorer
from app.session.settings import Settings
from evaluation.trials import NoTrial

CANVAS = Canvas(np.radians(50.0), 892.0, 720.0)
"""A 1280x720 window's canvas left of the docked control panel."""


def label_boxes(labels: labelling.Labels, pose, label_px: float) -> list[tuple[float, float, float, float]]:
    """(left, top, right, bottom) CSS pixels of each label seen through ``pose``."""
    spots = [framing.label_spot(text, x, y, label_px) for text, (x, y, _) in labels.values()]
    where = framing.project(*pose, CANVAS, np.array([(s.x, s.y) for s in spots]))
    return [(u, v, u + s.width, v + s.height) for (u, v), s in zip(where, spots)]


def overlapping(boxes: list[tuple[float, float, float, float]]) -> list[tuple[int, int]]:
    return [(i, j) for i, a in enumerate(boxes) for j, b in enumerate(boxes[:i])
            if a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]]


def test_spots_far_apart_all_show_inside_the_free_area_with_their_labels() -> None:
    spots = [Spot(0.0, 0.0), framing.label_spot("ego", 0.0, 0.0, 14.0), framing.label_spot("CAV", 47.0, -30.0, 14.0),
             framing.label_spot("missed 0ee9d30a", -20.0, 35.0, 14.0)]
    areas = framing.free_areas(CANVAS, Area(516.0, 16.0, 876.0, 160.0))
    pose = framing.frame(spots, CANVAS, areas)
    assert framing.inside_one(spots, *pose, CANVAS, areas)
    assert not framing.inside_one(spots, (5.0, 0.0, 60.0), (8.0, 0.0, 0.0), CANVAS, areas), \
        "the old fixed camera missed some (else this test proves nothing)"


def test_the_free_areas_lie_beside_and_below_a_corner_panel_and_the_closest_framing_wins() -> None:
    areas = framing.free_areas(CANVAS, Area(516.0, 16.0, 876.0, 160.0), margin=0.0)
    assert areas[:2] == [Area(0.0, 160.0, 892.0, 720.0), Area(0.0, 0.0, 516.0, 720.0)]
    tall = [Spot(-60.0, 0.0), Spot(60.0, 0.0)]
    wide = [Spot(0.0, -60.0), Spot(0.0, 60.0)]
    assert framing.frame(tall, CANVAS, areas) == framing.frame_in(tall, CANVAS, areas[1]), "the tall part beside"
    assert framing.frame(wide, CANVAS, areas) == framing.frame_in(wide, CANVAS, areas[0]), "the wide part below"


def test_the_key_numbers_area_grows_with_their_lines_and_wraps_long_ones() -> None:
    short = key_numbers_area("<b>Frame 1</b> · success<br>precision", CANVAS, 16.0, 360.0)
    long = key_numbers_area("<b>Frame 1</b> · success<br>" + "x" * 100, CANVAS, 16.0, 360.0)
    assert short.right == 876.0 and short.left == 516.0 and short.top == 16.0
    assert long.bottom - short.bottom == 2 * KEY_NUMBERS_LINE_PX, "100 characters wrap to 3 lines, 'precision' 1"


def test_labels_that_would_overprint_are_stacked_down_the_screen_agents_first() -> None:
    mpp = 0.08
    labels = {"pairs_after_missed_1_1": ("missed 0ee9d30a", (0.3, 0.2, 0.3)), "ego_after": ("ego", (0.0, 0.0, 0.3)),
              "a": ("✗ ego 1 ↔ CAV 2", (10.0, 0.0, 0.3)), "b": ("✗ ego 2 ↔ CAV 1", (9.8, -1.0, 0.3)),
              "c": ("missed 7", (10.0, 40.0, 0.3)), "picked": ("ego 5: matched", (10.0, 0.5, 0.3))}
    spread = labelling.spread(labels, mpp, 14.0)
    assert spread["ego_after"] == labels["ego_after"] and spread["a"] == labels["a"] and spread["c"] == labels["c"]
    assert spread["pairs_after_missed_1_1"][1][0] < labels["pairs_after_missed_1_1"][1][0]
    assert spread["b"][1][0] < labels["b"][1][0] and spread["picked"][1][0] < labels["picked"][1][0]
    height = mpp * CANVAS.focal
    pose = ((5.0, 0.0, height), (5.0 + 1e-3, 0.0, 0.0))
    assert overlapping(label_boxes(labels, pose, 14.0)), "the labels given overprint (else this proves nothing)"
    assert not overlapping(label_boxes(spread, pose, 14.0))


def test_a_failed_frame_with_three_cavs_is_framed_whole_outside_the_key_numbers(explorer: Explorer) -> None:
    outcome = explorer.compute(dataclasses.replace(Settings(frame=139), cavs=3))
    drawing = draw(outcome, explorer.map_segments)
    covered = Area(516.0, 16.0, 876.0, 250.0)
    areas = framing.free_areas(CANVAS, covered)
    pose = framing.frame(framing.spots_of(drawing), CANVAS, areas)
    assert framing.inside_one(framing.spots_of(drawing), *pose, CANVAS, areas)


FIXTURES = Path(__file__).resolve().parents[1] / "loaders" / "fixtures"


def first_outcome(explorer: Explorer, settings: Settings):
    """The outcome of the first frame the protocol finds an ego and a CAV on (INTERACTION's frame 0 has none)."""
    for frame in range(len(explorer)):
        try:
            return explorer.compute(dataclasses.replace(settings, frame=frame))
        except NoTrial:
            continue
    raise AssertionError("no frame with an ego and a CAV")


@pytest.mark.parametrize("dataset, protocol", [
    ("synthetic:60", None), ("argoverse2", None), (FIXTURES / "interaction" / "vehicle_tracks_000.csv", None),
    (FIXTURES / "sind" / "Xian_412_m1", "sind"), (FIXTURES / "opv2v" / "scenario", None),
    (FIXTURES / "v2v4real", None), (FIXTURES / "dair_v2x" / "cooperative-vehicle-infrastructure", "opv2v")])
def test_every_dataset_read_is_framed_whole_beside_the_key_numbers(dataset, protocol) -> None:
    explorer = Explorer(loaders.open(dataset))
    settings = Settings() if protocol is None else Settings().with_scenario(protocol=protocol)
    drawing = draw(first_outcome(explorer, settings), explorer.map_segments)
    areas = framing.free_areas(CANVAS, Area(516.0, 16.0, 876.0, 160.0))
    spots = framing.spots_of(drawing)
    assert len(spots) >= 4, "the ego, the CAV and their labels"
    assert framing.inside_one(spots, *framing.frame(spots, CANVAS, areas), CANVAS, areas)
