"""Helpers of the real-browser tests: Debian's chromium under Playwright, and ways to read the app's
page and wait for a tab's session."""
from __future__ import annotations

import contextlib
import dataclasses
import re
import shutil
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

CHROMIUM = shutil.which("chromium")
requires_chromium = pytest.mark.skipif(CHROMIUM is None,
                                       reason="Debian's chromium is not installed (make test installs it)")
ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
        "--disable-background-networking", "--disable-component-update", "--disable-sync",
        "--use-gl=angle", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"]
ARTIFACTS = Path(__file__).resolve().parents[1] / "_artifacts"
FIRST_SCREEN = {"width": 1280, "height": 720}
"""A projector's or a laptop's window: what must show in it without scrolling."""


def address(server, pixel_ratio: int = 1) -> str:
    """``server``'s address with the browser's drawing buffer held at ``pixel_ratio`` pixels per CSS
    pixel (the page's device scale factor): viser's client otherwise lowers its resolution to 0.875
    or 0.75 of it when frames come slowly (a loaded machine), and the camera the browser reports
    (``image_width``, ``image_height``) then changes size between a move and the test's check of it."""
    return f"{server.url}/?fixedDpr={pixel_ratio}"


def launch(sync_api) -> Iterator:
    """Yield a headless chromium (``sync_api``: ``playwright.sync_api``) and close it after."""
    with sync_api.sync_playwright() as playwright:
        launched = playwright.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield launched
        launched.close()


def open_page(browser, server):
    """A new tab on ``server``, once its first frame's metrics are shown."""
    page = browser.new_page(viewport={"width": 1400, "height": 900})
    page.goto(address(server))
    page.get_by_text("precision / recall").first.wait_for(timeout=30_000)
    return page


def open_first_screen(browser, server):
    """A new 1280x720 tab on ``server``, once its first frame's metrics are shown."""
    page = browser.new_page(viewport=FIRST_SCREEN)
    page.goto(address(server))
    page.get_by_text("precision / recall").first.wait_for(timeout=60_000)
    return page


def in_first_screen(locator) -> bool:
    """Whether ``locator`` shows whole in a 1280x720 window as it stands (no scrolling)."""
    box = locator.bounding_box()
    return box is not None and box["x"] >= 0 and box["y"] >= 0 \
        and box["x"] + box["width"] <= FIRST_SCREEN["width"] and box["y"] + box["height"] <= FIRST_SCREEN["height"]


def panel_tabs(page) -> list:
    """The control panel's tabs (Scenario, Method, ...), not those of the panels floating over the
    scene (the key numbers, presentation mode's caption)."""
    tablist = page.get_by_role("tablist").filter(has=page.get_by_role("tab", name="Scenario", exact=True))
    return tablist.get_by_role("tab").all()


def scene_canvas(page) -> dict:
    """The bounding box (CSS pixels) of the scene's canvas: the page's widest canvas."""
    return max((canvas.bounding_box() for canvas in page.locator("canvas").all()),
               key=lambda box: box["width"] if box else -1.0)


def metrics(page) -> str:
    return page.get_by_text("precision / recall").first.locator("xpath=ancestor::table").inner_text()


def header(page) -> str:
    return page.get_by_text(re.compile(r"^Frame \d+")).first.inner_text()


def label(page, text: str):
    """The GUI label whose whole text is ``text``."""
    return page.locator("label").filter(has_text=re.compile(f"^{re.escape(text)}$")).first


def slider(page, text: str):
    control = label(page, text).get_attribute("for")
    return page.locator(f'[id="{control}"] [role="slider"]')


def wait_until(condition: Callable[[], bool], timeout: float = 15.0) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, "timed out"
        time.sleep(0.1)


def settled_screenshot(page, timeout: float = 60.0) -> bytes:
    """The page's screenshot (PNG bytes) once two taken in a row are the same: closing notifications
    have faded and the scene has drawn its last frame (no fixed wait)."""
    deadline = time.monotonic() + timeout
    previous = page.screenshot()
    while (current := page.screenshot()) != previous:
        assert time.monotonic() < deadline, "the page never stood still"
        previous = current
    return current


def go_to_frame(page, tab, frame: int) -> None:
    """Type ``frame`` into the frame slider's number box and wait until the tab has computed it."""
    row = label(page, "frame").locator("xpath=ancestor::div[contains(@class, 'mantine-Flex-root')][1]")
    box = row.locator("input.mantine-NumberInput-input")
    box.fill(str(frame))
    box.press("Enter")
    wait_until(lambda: tab.last.frame_index == frame, 60)


def session(server, count: int):
    """The newest of at least ``count`` tab sessions, once every one has drawn its first frame."""
    wait_until(lambda: len(server.sessions) >= count and all(s.last for s in server.sessions.values()))
    return max(server.sessions.items())[1]


def pick_option(page, text: str, option: str) -> None:
    control = label(page, text).get_attribute("for")
    page.locator(f'[id="{control}"]').click()
    page.get_by_role("option", name=option, exact=True).click()


def load_preset(page, name: str) -> None:
    """Load the preset ``name`` from the Presets tab (the tab stays open)."""
    page.get_by_role("tab", name="Presets").click()
    pick_option(page, "preset", name)
    page.get_by_role("button", name="load", exact=True).click()


def over_time_tab(page, server, preset: str = "drift-heavy"):
    """The page's tab session once ``preset`` (one with CBM over time) is loaded and CBM over time computes."""
    tab = session(server, 1)
    close_notifications(page)
    load_preset(page, preset)
    wait_until(lambda: tab.last.settings.method == "cbm-time", 120)
    return tab


def close_notifications(page) -> None:
    for button in page.locator(".mantine-Notification-root button").all():
        button.click()


@contextlib.contextmanager
def scenario_server(explorer, presets_folder: Path, **scenario: Any) -> Iterator:
    """A running app on ``explorer`` whose tabs start with the default settings' scenario changed by
    ``scenario``, user presets in ``presets_folder``; stopped after."""
    from app.server import ExplorerServer
    from app.session.settings import Settings

    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("CBM_EXPLORER_PRESETS", str(presets_folder))
        settings = Settings()
        settings = dataclasses.replace(settings, scenario=dataclasses.replace(settings.scenario, **scenario))
        running = ExplorerServer(explorer, settings, port=0)
        yield running
        running.stop()
