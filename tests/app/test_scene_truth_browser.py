"""The picture is evidence (issue 24, items 1 to 3), read back from the browser's pixels: at RTE 0
a matched pair's footprints show on top of each other under the default camera; the boxes of a
wrong pair are marked themselves; every CAV is drawn as a CAV, and a click on its box names it."""
from __future__ import annotations

import contextlib
import dataclasses

import numpy as np
import pytest

from app.scene import planes
from app.scene.colours import CAV_COLOURS
from app.scene.drawing import draw
from app.scene.geometry import footprints
from app.scene.layouts import PANEL_PX
from app.server import ExplorerServer
from app.session.explorer import Explorer, classified_pairs
from app.session.presets import SHIPPED_DIR, read
from app.session.settings import Settings
from cbm import se2
from evaluation.diagnosis import short_id
from support import browser as ui
from support import pixels

pytestmark = [pytest.mark.browser, ui.requires_chromium]
FREE = (320.0, 200.0, 1280.0 - 440.0, 660.0)
"""(left, top, right, bottom) page pixels of the scene clear of the panel, the key numbers (floating at
the canvas's top, at most 190 px tall with three CAVs) and notifications."""
NEAR_M = 20.0
"""Metres from the ego within which a failed frame's wrong pair is framed."""
CANVAS = (24.0, 24.0, 1280.0 - 412.0, 696.0)
"""(left, top, right, bottom) page pixels of the canvas, less a margin (notifications closed)..."""
KEY_NUMBERS = (500.0, 0.0, 1280.0 - 388.0, 200.0)
"""... and of the key numbers floating at its top right."""


@contextlib.contextmanager
def running(explorer: Explorer, settings: Settings, presets) -> ExplorerServer:
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("CBM_EXPLORER_PRESETS", str(presets))
        server = ExplorerServer(explorer, settings, port=0)
        yield server
        server.stop()


def teaching(frame: int) -> Settings:
    """The teaching preset (no detection noise) at ``frame``, CAV boxes overlaid, ghosts on."""
    return read(SHIPPED_DIR / "teaching.toml", True).apply(Settings(frame=frame)).with_view(layout="overlay",
                                                                                            ghosts=True)


def settled_camera(tab):
    """The tab's camera once the browser has reported it, at the size of the canvas left of the panel,
    where the app last put it (a move still on its way would aim a click computed from it wrong)."""
    camera = tab.client.camera
    canvas = (1280 - PANEL_PX, 720)
    ui.wait_until(lambda: camera.update_timestamp and (camera.image_width, camera.image_height) == canvas
                  and tab.last is not None and tab.stage.camera.arrived, 60)
    return camera


def opened_at(browser, server: ExplorerServer, find) -> tuple:
    """(page, tab, camera, frame): the first screen opened, its camera settled, then moved to the
    frame ``find(settings, camera)`` picks."""
    page = ui.open_first_screen(browser, server)
    tab = ui.session(server, 1)
    camera = settled_camera(tab)
    frame = find(tab.last.settings, camera)
    if frame != tab.last.frame_index:
        ui.go_to_frame(page, tab, frame)
    return page, tab, camera, frame


def tilt(camera) -> float:
    """Degrees between the camera's line of sight and straight down."""
    sight = np.asarray(camera.look_at, float) - np.asarray(camera.position, float)
    return float(np.degrees(np.arccos(-sight[2] / np.linalg.norm(sight))))


def isolated_pair(outcome, camera) -> int:
    """The largest ego box of a right pair that shows in the free part of the page, 1.5 m clear of
    every other ego box and ground-truth outline, and of the two vehicles."""
    trial = outcome.trial
    boxes = np.concatenate([trial.ego_boxes, outcome.world_boxes])
    agents = np.array([[0.0, 0.0], outcome.result.transform[:2, 2]])
    best, area = -1, 0.0
    for i, _ in outcome.trial.gt_pairs:
        box = trial.ego_boxes[i]
        x, y = pixels.project(camera, np.array([[box[0], box[1], 0.0]]))[0]
        reach = np.hypot(box[3], box[4]) / 2 + 1.5
        gaps = np.hypot(*(boxes[:, :2] - box[:2]).T)
        crowded = np.count_nonzero(gaps < reach + np.hypot(boxes[:, 3], boxes[:, 4]) / 2) > 2
        near_agent = np.min(np.hypot(*(agents - box[:2]).T)) < reach + 3.0
        inside = FREE[0] < x < FREE[2] and FREE[1] < y < FREE[3]
        if inside and not crowded and not near_agent and box[3] * box[4] > area:
            best, area = int(i), float(box[3] * box[4])
    assert best >= 0, "no isolated matched pair in view"
    return best


def blue(image: np.ndarray) -> np.ndarray:
    r, g, b = (image[..., k].astype(int) for k in range(3))
    return (b > 150) & (b - r > 80) & (b > g + 30)


def orange(image: np.ndarray) -> np.ndarray:
    r, g, b = (image[..., k].astype(int) for k in range(3))
    return (r > 150) & (r - b > 100) & (g > b) & (g < r)


def test_a_right_pair_at_rte_0_shows_its_footprints_on_top_of_each_other(browser, explorer: Explorer,
                                                                          tmp_path) -> None:
    settings = teaching(10)
    with running(explorer, settings, tmp_path) as server:
        page = ui.open_first_screen(browser, server)
        tab = ui.session(server, 1)
        outcome = tab.last
        assert outcome.metrics.rte < 0.005 and outcome.metrics.n_correct == outcome.metrics.n_matched > 0
        camera = settled_camera(tab)
        ui.close_notifications(page)
        image = pixels.screenshot(page)
        i = isolated_pair(outcome, camera)
        box = outcome.trial.ego_boxes[i]
        corners = pixels.project(camera, np.c_[footprints(box[None])[0], np.zeros(4)])
        centre = pixels.project(camera, np.array([[box[0], box[1], 0.0]]))[0]
        low, high = np.floor(corners.min(axis=0)).astype(int) - 10, np.ceil(corners.max(axis=0)).astype(int) + 10
        window = np.zeros(image.shape[:2], bool)
        window[low[1]:high[1], low[0]:high[0]] = True
        cav, ego = orange(image) & window, (blue(image) | orange(image)) & window
        top_down = tilt(camera)
        page.get_by_role("tab", name="View").click()
        page.get_by_role("button", name="3D view").click()
        ui.wait_until(lambda: tilt(camera) > 30.0, 30)
        page.get_by_role("button", name="reset camera").click()
        ui.wait_until(lambda: tilt(camera) < 5.0, 30)
        page.close()
    assert cav.sum() > 20, f"no CAV footprint on ego box {i} at {centre}"
    ego_middle, cav_middle = middle(ego), middle(cav)
    assert np.linalg.norm(cav_middle - ego_middle) < 1.5, (cav_middle, ego_middle)
    assert np.linalg.norm(ego_middle - centre) < 2.0, (ego_middle, centre)
    spans = corners.max(axis=0) - corners.min(axis=0)
    assert np.allclose(extent(ego), spans, atol=3.0), (extent(ego), spans)
    assert top_down < 5.0


def middle(mask: np.ndarray) -> np.ndarray:
    """(x, y) middle of the pixels of ``mask``'s bounding rectangle (lines drawn across it do not move it)."""
    ys, xs = np.nonzero(mask)
    return np.array([(xs.min() + xs.max()) / 2, (ys.min() + ys.max()) / 2])


def extent(mask: np.ndarray) -> np.ndarray:
    ys, xs = np.nonzero(mask)
    return np.array([xs.max() - xs.min() + 1, ys.max() - ys.min() + 1], float)


def red(image: np.ndarray) -> np.ndarray:
    r, g, b = (image[..., k].astype(int) for k in range(3))
    return (r > 190) & (r - g > 90) & (abs(g - b) < 45)


def overlapping_wrong_gaps(outcome) -> np.ndarray:
    """Per wrong pair of ``outcome``, the distance (m) between its ego box and its placed CAV box."""
    _, wrong, _ = classified_pairs(outcome.result.pairs, outcome.trial.gt_pairs)
    cav = se2.apply_boxes(outcome.result.transform, outcome.trial.cav_boxes)
    return np.hypot(*(outcome.trial.ego_boxes[wrong[:, 0], :2] - cav[wrong[:, 1], :2]).T)


def frame_with_an_overlapping_wrong_pair(explorer: Explorer, settings: Settings, camera) -> int:
    """The first frame where CBM pairs two boxes less than 0.5 m apart wrongly (the line of such a
    pair has no length), near the ego (the camera frames a failed frame's wrong pairs nearest first)."""
    for frame in range(len(explorer)):
        outcome = explorer.compute(dataclasses.replace(settings, frame=frame))
        _, wrong, _ = classified_pairs(outcome.result.pairs, outcome.trial.gt_pairs)
        if len(wrong) and ((np.hypot(*outcome.trial.ego_boxes[wrong[:, 0], :2].T) < NEAR_M)
                           & (overlapping_wrong_gaps(outcome) < 0.5)).any():
            return frame
    raise AssertionError("no frame with a wrong pair whose boxes overlap in view")


def test_a_wrong_pair_whose_boxes_overlap_is_marked_on_its_boxes(browser, explorer: Explorer, tmp_path) -> None:
    settings = read(SHIPPED_DIR / "stress.toml", True).apply(Settings(frame=0))
    with running(explorer, settings, tmp_path) as server:
        page, tab, camera, frame = opened_at(browser, server, lambda settings, camera:
                                             frame_with_an_overlapping_wrong_pair(explorer, settings, camera))
        ui.wait_until(lambda: ui.header(page) == f"Frame {frame}", 60)
        camera = settled_camera(tab)
        outcome, drawing = tab.last, tab.last_drawing
        assert outcome.metrics.n_matched > outcome.metrics.n_correct
        ui.close_notifications(page)
        image = pixels.screenshot(page)
        i, j = overlapping_wrong_pair(outcome, camera)
        box = outcome.trial.ego_boxes[i]
        corners = pixels.project(camera, np.c_[footprints(box[None])[0], np.zeros(4)])
        low, high = np.floor(corners.min(axis=0)).astype(int) - 6, np.ceil(corners.max(axis=0)).astype(int) + 6
        marked = red(image)[low[1]:high[1], low[0]:high[0]].sum()
        perimeter = np.sum(np.linalg.norm(corners - np.roll(corners, 1, axis=0), axis=1))
        assert marked > perimeter, f"{marked} red pixels on wrong pair {i, j}, outline {perimeter:.0f} px long"
        ego_id, cav_id = str(outcome.trial.ego_ids[i])[:8], str(outcome.trial.cav_ids[j])[:8]
        label = tab.stage.view.labels[f"pairs_after_wrong_{i}_{j}"]
        assert label.visible and ego_id in label.text and cav_id in label.text, label.text
        page.close()
    assert len(drawing.lines["wrong_marks"].segments) == 8 * (outcome.metrics.n_matched - outcome.metrics.n_correct)


def in_free_part(camera, xy: np.ndarray) -> np.ndarray:
    """Whether each ego-frame point (N, 2) on the ground shows in the free part of the page."""
    where = pixels.project(camera, np.c_[xy, np.zeros(len(xy))])
    return (FREE[0] < where[:, 0]) & (where[:, 0] < FREE[2]) & (FREE[1] < where[:, 1]) & (where[:, 1] < FREE[3])


def within(where: np.ndarray, box: tuple[float, float, float, float]) -> np.ndarray:
    return (box[0] < where[:, 0]) & (where[:, 0] < box[2]) & (box[1] < where[:, 1]) & (where[:, 1] < box[3])


def overlapping_wrong_pair(outcome, camera) -> tuple[int, int]:
    """The wrong pair (ego row, CAV row) in the free part of the page whose drawn boxes are closest
    (its match line shortest), less than half a metre apart."""
    _, wrong, _ = classified_pairs(outcome.result.pairs, outcome.trial.gt_pairs)
    gaps = overlapping_wrong_gaps(outcome)
    where = pixels.project(camera, np.c_[outcome.trial.ego_boxes[wrong[:, 0], :2], np.zeros(len(wrong))])
    inside = within(where, CANVAS) & ~within(where, KEY_NUMBERS)
    assert inside.any(), "no wrong pair in view"
    k = int(np.argmin(np.where(inside, gaps, np.inf)))
    assert gaps[k] < 0.5, gaps[k]
    return int(wrong[k, 0]), int(wrong[k, 1])


def test_three_cavs_each_have_a_vehicle_label_lines_legend_and_key_numbers(browser, explorer: Explorer,
                                                                          tmp_path) -> None:
    settings = dataclasses.replace(Settings(frame=10), cavs=3)
    with running(explorer, settings, tmp_path) as server:
        page = ui.open_first_screen(browser, server)
        tab = ui.session(server, 1)
        outcome = tab.last
        assert len(outcome.others) == 2
        ui.wait_until(lambda: "CAV 3" in page.locator("#cbm-key-numbers").inner_text(), 30)
        key_numbers = page.locator("#cbm-key-numbers").inner_text()
        page.get_by_role("tab", name="View").click()
        legend = page.get_by_text("CAVs:").first.inner_text()
        view = tab.stage.view
        for rank, colour in ((2, CAV_COLOURS[0]), (3, CAV_COLOURS[1])):
            vehicle = view.meshes[f"cav_vehicle_{rank}"]
            assert vehicle.visible and tuple(vehicle.color) == colour
            assert view.labels[f"cav_{rank}_after"].visible and view.labels[f"cav_{rank}_after"].text == f"CAV {rank}"
            assert f"CAV {rank}" in legend and f"CAV {rank} ·" in key_numbers
        page.close()
    pairs = sum(len(cav.result.pairs) for cav in (outcome, *outcome.others))
    assert len(tab.last_drawing.lines["right"].segments) == pairs == outcome.metrics.n_correct + sum(
        other.metrics.n_correct for other in outcome.others)
    assert "CAV 1 ·" in key_numbers and "3 of 3 CAVs succeed" in key_numbers


def test_a_click_on_a_third_cavs_box_names_that_cav(browser, explorer: Explorer, tmp_path) -> None:
    """A click on CAV 3's footprint labels that box with CAV 3's name and its id: one nested on top of
    the ego's and the other CAVs' of the same object, and one of an object neither the ego nor CAV 1
    sees (no footprint of theirs under it: CAV 3's own node answers the click)."""
    settings = Settings(frame=10)
    settings = dataclasses.replace(settings, cavs=3, scenario=dataclasses.replace(settings.scenario, sensor_range=25.0))
    # The camera stays where the first frame put it: the frame to click on is chosen under that camera.
    with running(explorer, settings.with_view(follow=False), tmp_path) as server:
        page, tab, camera, frame = opened_at(browser, server, lambda settings, camera:
                                             frame_with_cav3_boxes_in_view(explorer, settings, camera))
        ui.close_notifications(page)
        outcome, drawing = tab.last, tab.last_drawing
        boxes, rows = drawing.objects["cav_3"]
        picked = lambda: tab.stage.view.labels.get("picked")  # noqa: E731
        for alone in (False, True):
            settled_camera(tab)
            row = largest(boxes, clickable(outcome, drawing, camera, alone))
            x, y = pixels.project(camera, np.array([[*boxes[row, :2], planes.cav(3)]]))[0]
            page.mouse.click(x, y)
            expected = f"CAV 3 {short_id(outcome.others[1].trial.cav_ids[rows[row]])}"
            ui.wait_until(lambda text=expected: picked() is not None and picked().visible
                          and picked().text.startswith(text), 30)
        page.close()


def frame_with_cav3_boxes_in_view(explorer: Explorer, settings: Settings, camera) -> int:
    """The first frame from ``settings``' on with both kinds of ``clickable`` boxes of CAV 3."""
    for frame in range(settings.frame, len(explorer)):
        outcome = explorer.compute(dataclasses.replace(settings, frame=frame))
        drawing = draw(outcome, {})
        if all(clickable(outcome, drawing, camera, alone).any() for alone in (False, True)):
            return frame
    raise AssertionError("no frame with boxes of CAV 3 to click in view")


def clickable(outcome, drawing, camera, alone: bool) -> np.ndarray:
    """Which drawn boxes of CAV 3 show in the free part of the page, 4 m clear of every label and
    vehicle, with an object the ego sees too (its footprint under CAV 3's) or (``alone``) neither the
    ego nor CAV 1 sees."""
    boxes, rows = drawing.objects["cav_3"]
    ids = outcome.others[1].trial.cav_ids[rows]
    others = np.concatenate([outcome.trial.ego_ids, outcome.trial.cav_ids])
    seen = ~np.isin(ids, others) if alone else np.isin(ids, outcome.trial.ego_ids)
    marks = np.array([[*position[:2]] for _, position in drawing.labels.values()] + list(drawing.agents))
    clear = np.array([np.min(np.hypot(*(marks - box[:2]).T)) > 4.0 for box in boxes], dtype=bool)
    return seen & clear & in_free_part(camera, boxes[:, :2])


def largest(boxes: np.ndarray, chosen: np.ndarray) -> int:
    """The row of the largest footprint among the ``chosen`` boxes."""
    return int(np.argmax(np.where(chosen, boxes[:, 3] * boxes[:, 4], -1.0)))
