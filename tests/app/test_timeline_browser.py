"""The timeline in the metrics area: it fills as frames are computed (stepping, run all frames), marks
the failed frames (``evaluation.metrics.is_success``), and its controls step to and jump to them:
past the last failure *next failure* goes round to the first and says so, and *jump to* shows the
frame on screen, not the one picked last."""
from __future__ import annotations

import dataclasses
import io

import numpy as np
import pytest
from PIL import Image

from app.server import ExplorerServer
from app.session.explorer import Explorer
from app.session.settings import Settings
from evaluation.metrics import is_success
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]

SCENARIO = dict(protocol="sind", sigma_p=1.2, sigma_theta=10.0, seed=2)
"""A noisy scenario under which a few frames of the synthetic scene fail."""


@pytest.fixture(scope="module")
def server(small_explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(small_explorer, tmp_path_factory.mktemp("presets"), **SCENARIO) as running:
        yield running


@pytest.fixture(scope="module")
def failed(small_explorer: Explorer) -> list[int]:
    """The frames that fail under ``SCENARIO`` (RTE >= 1 m or RRE >= 1 deg), computed apart from the
    app: at least two, the first after frame 0 (where the page opens)."""
    settings = Settings()
    settings = dataclasses.replace(settings, scenario=dataclasses.replace(settings.scenario, **SCENARIO))
    frames = [frame for frame in range(len(small_explorer))
              if not is_success(small_explorer.compute(dataclasses.replace(settings, frame=frame)).metrics)]
    assert len(frames) >= 2 and frames[0] > 0, frames
    return frames


def pixels_of(page, colour: tuple[int, int, int]) -> int:
    """How many pixels of the timeline's chart have (nearly) ``colour``."""
    png = page.locator(".uplot").filter(has_text="timeline").first.screenshot()
    image = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)
    return int((np.abs(image - np.array(colour)).sum(axis=2) < 40).sum())


def plotted_frames(tab) -> set[int]:
    """Frames whose precision the timeline's chart holds (it is drawn a moment after each result)."""
    x, precision = tab.controls.metrics.plot.data[:2]
    return set(x[np.isfinite(precision)].astype(int).tolist())


def frame_shown(tab, frame: int) -> bool:
    return tab.last is not None and tab.last.frame_index == frame and tab.settings.frame == frame


def test_stepping_fills_the_timeline_and_a_settings_change_of_the_view_keeps_it(browser,
                                                                                 server: ExplorerServer) -> None:
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    ui.close_notifications(page)
    for frame in (1, 2, 3):
        page.get_by_role("button", name="next ▶").click()
        ui.wait_until(lambda f=frame: frame_shown(tab, f), 60)
    ui.wait_until(lambda: {0, 1, 2, 3} <= plotted_frames(tab), 30)
    ui.wait_until(lambda: pixels_of(page, (30, 156, 60)) > 30, 30)
    page.get_by_role("tab", name="View").click()
    ui.label(page, "ground-truth ghosts").click()
    ui.wait_until(lambda: tab.last.settings.view.ghosts, 60)
    assert set(tab.history.rows) == {0, 1, 2, 3}
    page.close()


def test_run_all_frames_fills_the_timeline_and_failures_are_stepped_through(browser, server: ExplorerServer,
                                                                           failed: list[int]) -> None:
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    ui.close_notifications(page)
    page.get_by_role("button", name="next failure ▶").click()
    page.get_by_text("run all frames (Explore tab) to find every failure").first.wait_for(timeout=15_000)
    page.get_by_role("tab", name="Explore").click()
    page.get_by_role("button", name="run all frames").click()
    ui.wait_until(lambda: len(tab.history.rows) == len(tab.explorer), 180)
    assert tab.history.failures() == failed
    ui.wait_until(lambda: pixels_of(page, (192, 20, 30)) > 20, 30)
    page.get_by_role("button", name="next failure ▶").click()
    ui.wait_until(lambda: frame_shown(tab, failed[0]), 60)
    page.get_by_role("button", name="next failure ▶").click()
    ui.wait_until(lambda: frame_shown(tab, failed[1]), 60)
    page.get_by_role("button", name="◀ previous failure").click()
    ui.wait_until(lambda: frame_shown(tab, failed[0]), 60)
    ui.pick_option(page, "jump to", f"frame {failed[1]}")
    ui.wait_until(lambda: frame_shown(tab, failed[1]), 60)
    ui.wait_until(lambda: f"Frame {failed[1]}" == ui.header(page), 30)
    click_timeline_at(page, failed, len(tab.explorer))
    ui.wait_until(lambda: frame_shown(tab, failed[0]), 60)
    page.close()


def click_timeline_at(page, failed: list[int], n_frames: int) -> None:
    """Click the frame slider where the first failed frame lies, after checking it marks every
    failed frame (besides its two labelled ends)."""
    frame = failed[0]
    control = ui.label(page, "frame").get_attribute("for")
    root = page.locator(f'[id="{control}"]')
    ui.wait_until(lambda: root.locator(".mantine-Slider-mark").count() == len(failed) + 2, 30)
    root.scroll_into_view_if_needed()
    track = root.locator(".mantine-Slider-track").bounding_box()
    page.mouse.click(track["x"] + track["width"] * frame / (n_frames - 1), track["y"] + track["height"] / 2)


def jump_list(page) -> str:
    """What the *jump to* list shows."""
    return page.locator(f'[id="{ui.label(page, "jump to").get_attribute("for")}"]').input_value()


def test_next_failure_wraps_with_a_message_and_jump_to_follows_the_frame(browser, server: ExplorerServer,
                                                                         failed: list[int]) -> None:
    page = ui.open_first_screen(browser, server)
    tab = ui.session(server, 1)
    page.get_by_role("tab", name="Explore").click()
    page.get_by_role("button", name="run all frames").click()
    ui.wait_until(lambda: len(tab.history.rows) == len(tab.explorer), 180)
    ui.close_notifications(page)
    for frame in (*failed, failed[0]):
        page.get_by_role("button", name="next failure ▶").click()
        ui.wait_until(lambda f=frame: frame_shown(tab, f), 60)
    page.get_by_text(f"back to the first, frame {failed[0]}").first.wait_for(timeout=30_000)
    page.get_by_text("Past the last failure").first.wait_for(timeout=30_000)
    ui.wait_until(lambda: jump_list(page) == f"frame {failed[0]}", 30)
    page.get_by_role("button", name="◀ previous failure").click()
    ui.wait_until(lambda: frame_shown(tab, failed[-1]), 60)
    page.get_by_text(f"back to the last, frame {failed[-1]}").first.wait_for(timeout=30_000)

    ui.pick_option(page, "jump to", f"frame {failed[0]}")
    ui.wait_until(lambda: frame_shown(tab, failed[0]), 60)
    page.get_by_role("button", name="next ▶").click()
    ui.wait_until(lambda: frame_shown(tab, failed[0] + 1), 60)
    ui.wait_until(lambda: jump_list(page).startswith("failed frames"), 30)
    page.close()
