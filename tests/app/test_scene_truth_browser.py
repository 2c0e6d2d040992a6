"""The picture is evidence (issue 24, items 1 to 3), read back from the browser's pixels: at RTE 0
a matched pair's footprints show on top of each other under the default camera; the boxes of a
wrong pair are marked themselves; every CAV is drawn as a CAV."""
from __future__ import annotations

import contextlib

import numpy as np
import pytest

from app.scene.geometry import footprints
from app.server import ExplorerServer
from app.session.explorer import Explorer
from app.session.presets import SHIPPED_DIR, read
from app.session.settings import Settings
from support import browser as ui
from support import pixels

pytestmark = [pytest.mark.browser, ui.requires_chromium]
FREE = (320.0, 100.0, 1280.0 - 440.0, 660.0)
"""(left, top, right, bottom) page pixels of the scene clear of the panel, the key numbers and notifications."""


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
    """The tab's camera once the browser has reported it, at the page's size."""
    camera = tab.client.camera
    ui.wait_until(lambda: camera.update_timestamp and camera.image_width == 1280 and camera.image_height == 720, 60)
    return camera


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
        page.wait_for_timeout(1500)
        image = pixels.screenshot(page)
        i = isolated_pair(outcome, camera)
        box = outcome.trial.ego_boxes[i]
        corners = pixels.project(camera, np.c_[footprints(box[None])[0], np.zeros(4)])
        centre = pixels.project(camera, np.array([[box[0], box[1], 0.0]]))[0]
        low, high = np.floor(corners.min(axis=0)).astype(int) - 10, np.ceil(corners.max(axis=0)).astype(int) + 10
        window = np.zeros(image.shape[:2], bool)
        window[low[1]:high[1], low[0]:high[0]] = True
        cav, ego = orange(image) & window, (blue(image) | orange(image)) & window
        page.close()
    assert cav.sum() > 20, f"no CAV footprint on ego box {i} at {centre}"
    ego_middle, cav_middle = middle(ego), middle(cav)
    assert np.linalg.norm(cav_middle - ego_middle) < 1.5, (cav_middle, ego_middle)
    assert np.linalg.norm(ego_middle - centre) < 2.0, (ego_middle, centre)
    spans = corners.max(axis=0) - corners.min(axis=0)
    assert np.allclose(extent(ego), spans, atol=3.0), (extent(ego), spans)
    assert tilt(camera) < 5.0


def middle(mask: np.ndarray) -> np.ndarray:
    """(x, y) middle of the pixels of ``mask``'s bounding rectangle (lines drawn across it do not move it)."""
    ys, xs = np.nonzero(mask)
    return np.array([(xs.min() + xs.max()) / 2, (ys.min() + ys.max()) / 2])


def extent(mask: np.ndarray) -> np.ndarray:
    ys, xs = np.nonzero(mask)
    return np.array([xs.max() - xs.min() + 1, ys.max() - ys.min() + 1], float)
