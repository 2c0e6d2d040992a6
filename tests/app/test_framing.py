"""Where the camera frames what explains a frame, and labels beside their boxes: the geometry, without a
browser (issue 39 items 1-2, issue 47 items 1-2)."""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import loaders
from app.scene import focus, framing, labelling
from app.scene.camera import KEY_NUMBERS_LINE_PX, TabCamera, key_numbers_area
from app.scene.drawing import draw
from app.scene.framing import Area, Canvas, Spot
from app.session.explorer import Explorer
from app.session.presets import discover
from app.session.settings import Settings
from evaluation.trials import NoTrial

CANVAS = Canvas(np.radians(75.0), 892.0, 720.0)
"""A 1280x720 window's canvas left of the docked control panel, with the field of view chromium reports."""
COVERED = Area(516.0, 16.0, 876.0, 190.0)
"""The key numbers of a failed frame, at the canvas's top right."""
HEAVY = (45, 34, 7, 22)
"""Failed frames of the shipped scene under the heavy-noise preset (issue 47)."""


def camera() -> TabCamera:
    """A tab camera on a 892x720 canvas, without a browser (``_framed`` reads only the canvas)."""
    made = TabCamera.__new__(TabCamera)
    made.client = SimpleNamespace(camera=SimpleNamespace(fov=CANVAS.fov, image_width=892, image_height=720,
                                                         update_timestamp=1.0))
    return made


def heavy(frame: int, **changes) -> Settings:
    settings = discover()[0]["heavy-noise"].apply(Settings())
    return dataclasses.replace(settings, frame=frame, **changes)


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


def test_a_tall_framing_beside_the_panel_moves_to_the_canvas_middle_when_it_clears_the_panel() -> None:
    covered = Area(516.0, 16.0, 876.0, 160.0)
    tall = [Spot(-40.0, 0.0), Spot(25.0, 0.0)]
    pose = framing.frame(tall, CANVAS, framing.free_areas(CANVAS, covered))
    moved = framing.balanced(tall, pose, CANVAS, covered)
    assert framing.metres_per_px(*moved, CANVAS) == pytest.approx(framing.metres_per_px(*pose, CANVAS), rel=0.01)
    middle = framing.project(*moved, CANVAS, np.array([(s.x, s.y) for s in tall]))[:, 0].mean()
    assert abs(middle - CANVAS.width / 2) < 2 and framing.project(*pose, CANVAS, np.zeros((1, 2)))[0, 0] < 300
    near_panel = [Spot(30.0, -30.0), Spot(-30.0, 30.0)]
    pose = framing.frame(near_panel, CANVAS, framing.free_areas(CANVAS, covered))
    assert framing.balanced(near_panel, pose, CANVAS, covered) == pose, "centred, a spot would lie under the panel"


def test_the_key_numbers_area_grows_with_their_lines_and_wraps_long_ones() -> None:
    short = key_numbers_area("<b>Frame 1</b> · success<br>precision", CANVAS, 16.0, 360.0)
    long = key_numbers_area("<b>Frame 1</b> · success<br>" + "x" * 100, CANVAS, 16.0, 360.0)
    assert short.right == 876.0 and short.left == 516.0 and short.top == 16.0
    assert long.bottom - short.bottom == 2 * KEY_NUMBERS_LINE_PX, "100 characters wrap to 3 lines, 'precision' 1"


def test_labels_sit_beside_their_boxes_never_overprint_and_a_crowd_keeps_the_ones_that_matter() -> None:
    mpp, px = 0.08, 14.0
    labels = {"ego_after": ("ego", (0.0, 0.0, 0.3)), "a": ("✗ ego 1 ↔ CAV 2", (10.0, 0.0, 0.3)),
              "b": ("✗ ego 2 ↔ CAV 1", (9.8, -1.0, 0.3)), "c": ("missed 7", (10.0, 40.0, 0.3)),
              "pairs_after_missed_1_1": ("missed 0ee9d30a", (0.3, 0.2, 0.3)),
              "picked": ("ego 5: matched", (10.0, 0.5, 0.3))}
    room = {name: (1.0, 2.3) for name in labels}
    laid = labelling.lay_out(labels, mpp, px, room)
    assert set(laid.labels) == set(labels) and not laid.hidden
    (_, (x, y, _)), half = laid.labels["ego_after"], room["ego_after"]
    assert x == pytest.approx(px * labelling.LINE_EM / 2 * mpp), "level with its vehicle"
    assert y == pytest.approx(-half[0] - labelling.GAP_PX * mpp), "the ego's label starts just right of its vehicle"
    height = mpp * CANVAS.focal
    pose = ((5.0, 0.0, height), (5.0 + 1e-3, 0.0, 0.0))
    assert overlapping(label_boxes(labels, pose, px)), "the labels given overprint (else this proves nothing)"
    assert not overlapping(label_boxes(laid.labels, pose, px))
    moved = [name for name in labels if math.dist(laid.labels[name][1][:2], labels[name][1][:2]) > 0]
    assert len(laid.leaders) <= len(moved) and all(len(segment) == 2 for segment in laid.leaders)

    crowd = {f"pairs_after_wrong_{k}_{k}": (f"✗ ego {k:08d} ↔ CAV {k:08d}", (0.0, 0.1 * k, 0.3)) for k in range(30)}
    kept = frozenset(list(crowd)[:3])
    far = labelling.lay_out(crowd, 0.5, px, {}, kept)
    assert kept <= set(far.labels) and far.hidden and not (kept & far.hidden), "the failure's labels stay"
    assert not overlapping(label_boxes(far.labels, ((0.0, 0.0, 0.5 * CANVAS.focal), (1e-3, 0.0, 0.0)), px))


@pytest.mark.parametrize("frame", HEAVY)
def test_a_failed_heavy_noise_frame_frames_its_deciding_pairs_with_cars_readable(explorer: Explorer,
                                                                                 frame: int) -> None:
    """Issue 47: frame 45 was framed from 227 m, its boxes specks and its labels in a column."""
    drawing = draw(explorer.compute(heavy(frame)), explorer.map_segments)
    pose, aim = camera()._framed(drawing, COVERED)
    shown = [mark for mark in drawing.marks if mark not in aim.away]
    assert framing.metres_per_px(*pose, CANVAS) <= focus.READABLE * 1.1, "a car stays a readable box"
    assert any(mark.deciding for mark in shown), "a pair CBM's answer rests on is in view"
    for mark in shown:
        assert focus.in_sight(mark.points, pose, CANVAS, COVERED), mark.key
    assert focus.in_sight(np.array(drawing.agents), pose, CANVAS, COVERED), "the ego and the CAV"
    assert all(not focus.in_sight(mark.points, pose, CANVAS, COVERED) for mark in aim.away)
    assert len(shown) + len(aim.away) == len(drawing.marks)


def test_the_camera_zooms_back_in_on_a_frame_that_needs_less(explorer: Explorer) -> None:
    tab = camera()
    failed, _ = tab._framed(draw(explorer.compute(heavy(45)), explorer.map_segments), COVERED)
    success, _ = tab._framed(draw(explorer.compute(heavy(0)), explorer.map_segments), COVERED)
    assert success[0][2] == pytest.approx(framing.LOWEST, rel=0.01) and failed[0][2] > framing.LOWEST * 1.1


def test_side_by_side_frames_both_halves(explorer: Explorer) -> None:
    drawing = draw(explorer.compute(heavy(45).with_view(layout="side by side")), explorer.map_segments)
    pose, _ = camera()._framed(drawing, COVERED)
    assert len(drawing.agents) == 4 and focus.in_sight(np.array(drawing.agents), pose, CANVAS, COVERED)
    for title in ("before", "after"):
        assert focus.in_sight(np.array([drawing.labels[title][1][:2]]), pose, CANVAS, COVERED)


def test_a_failed_frame_with_three_cavs_is_framed_outside_the_key_numbers(explorer: Explorer) -> None:
    drawing = draw(explorer.compute(dataclasses.replace(Settings(frame=139), cavs=3)), explorer.map_segments)
    pose, aim = camera()._framed(drawing, COVERED)
    assert focus.in_sight(np.array(drawing.agents), pose, CANVAS, COVERED)
    assert all(focus.in_sight(m.points, pose, CANVAS, COVERED) for m in drawing.marks if m not in aim.away)


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
    pose, aim = camera()._framed(drawing, COVERED)
    assert len(drawing.agents) >= 2
    assert focus.in_sight(np.array(drawing.agents), pose, CANVAS, COVERED), "the ego and the CAV"
    laid = labelling.lay_out(drawing.labels, aim.scale, drawing.label_px, drawing.room, drawing.kept)
    names = [name for name in laid.labels if name.startswith(("ego", "cav"))]
    assert len(names) >= 2 and framing.all_inside(
        [framing.label_spot(laid.labels[n][0], *laid.labels[n][1][:2], drawing.label_px) for n in names], *pose, CANVAS,
        Area(0.0, 0.0, CANVAS.width, CANVAS.height)), "their labels whole on the canvas"
