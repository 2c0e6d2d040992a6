"""CBM over time in a browser: the preset picks it, a jump ahead computes the frames before in order,
and the metrics and the timeline show how the answer was reached beside per-frame CBM."""
from __future__ import annotations

import threading

import pytest

from app.session.explorer import Explorer
from app.session.over_time import Runs
from app.walkthrough import steps
from app.walkthrough.nodes import ROOT
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]


@pytest.fixture(scope="module")
def server(small_explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(small_explorer, tmp_path_factory.mktemp("presets")) as running:
        yield running


def held_at_third(steps: list[int], release: threading.Event):
    """``Runs._step`` recording each frame it steps in ``steps`` and holding the third until ``release``."""
    step = Runs._step

    def held(run, settings, j, trial_of) -> None:
        steps.append(j)
        if len(steps) == 3:
            release.wait(60)
        step(run, settings, j, trial_of)
    return staticmethod(held)


def test_choosing_cbm_over_time_and_jumping_ahead_shows_the_frames_pooled(browser, server) -> None:
    page = ui.open_page(browser, server)
    tab = ui.over_time_tab(page, server)
    ui.go_to_frame(page, tab, 25)
    ui.wait_until(lambda: "answer from" in ui.metrics(page) or "this frame alone" in ui.metrics(page), 60)
    assert "over time" in ui.metrics(page) and "per-frame CBM (this frame)" in ui.metrics(page)
    ui.wait_until(lambda: set(range(26)) <= set(tab.history.rows), 60)
    ui.wait_until(lambda: page.locator(".uplot").filter(has_text="per-frame CBM RTE").count() == 1, 30)
    page.close()


def test_the_stop_button_stops_a_jump_ahead_and_keeps_the_frames_done(browser, server, monkeypatch) -> None:
    """The catch-up is held at its third frame until the stop button was clicked, so the click
    always lands while frames are still being computed, however busy the machine."""
    clicked, steps = threading.Event(), []
    monkeypatch.setattr(Runs, "_step", held_at_third(steps, clicked))
    page = ui.open_page(browser, server)
    tab = ui.over_time_tab(page, server)
    steps.clear()
    ui.label(page, "frame").locator("xpath=ancestor::div[contains(@class, 'mantine-Flex-root')][1]") \
        .locator("input.mantine-NumberInput-input").fill("49")
    page.keyboard.press("Enter")
    stop = page.get_by_role("button", name="stop computing the frames before")
    stop.wait_for(state="visible", timeout=60_000)
    stop.click()
    ui.wait_until(lambda: tab._stop_catching_up.is_set(), 30)
    clicked.set()
    ui.wait_until(lambda: page.get_by_text("Stopped", exact=True).count() > 0, 60)
    last = steps[-1]
    ui.wait_until(lambda: tab.last.frame_index == last and tab.settings.frame == last, 60)
    assert last < 49
    assert set(tab.explorer.over_time.done(tab.settings)) >= set(range(last + 1))
    steps.clear()
    ui.go_to_frame(page, tab, last + 2)
    assert steps == [last + 1, last + 2]
    page.close()


def test_an_edit_deep_in_the_sequence_shows_per_frame_cbm_at_once_marked_until_the_answer_over_time(
        browser, server, monkeypatch) -> None:
    """The catch-up under the edited σp is held at its third frame until the page showed the frame
    with per-frame CBM's answer, marked, so the preview is seen however busy the machine."""
    seen, steps = threading.Event(), []
    page = ui.open_page(browser, server)
    tab = ui.over_time_tab(page, server)
    ui.go_to_frame(page, tab, 49)
    monkeypatch.setattr(Runs, "_step", held_at_third(steps, seen))
    page.get_by_role("tab", name="Scenario").click()
    control = ui.label(page, "position noise σp (m)").get_attribute("for")
    page.locator(f'[id="{control}"]').locator("xpath=ancestor::div[contains(@class, 'mantine-Flex-root')][1]") \
        .locator("input.mantine-NumberInput-input").fill(f"{tab.settings.scenario.sigma_p + 0.01:g}")
    preview = page.get_by_text("shown while CBM over time computes the frames before it")
    preview.first.wait_for(timeout=60_000)
    assert "over time" not in ui.metrics(page) and len(steps) <= 3
    ui.wait_until(lambda: "per-frame CBM shown meanwhile" in page.locator("#cbm-key-numbers").inner_text(), 60)
    seen.set()
    ui.wait_until(lambda: tab.last is not None and tab.last.settings == tab.settings and preview.count() == 0, 120)
    assert "over time" in ui.metrics(page) and len(steps) == 50
    page.close()


def test_the_scenario_tab_offers_the_drifting_error_and_the_steps_end_over_time(browser, server) -> None:
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    ui.close_notifications(page)
    page.get_by_role("tab", name="Scenario").click()

    def live(text: str) -> bool:
        control = page.locator(f'[id="{ui.label(page, text).get_attribute("for")}"]')
        return control.locator('[role="slider"]').first.get_attribute("data-disabled") != "true"

    assert not live("drift time constant (s)")
    ui.pick_option(page, "localization error", "drifting")
    ui.wait_until(lambda: tab.settings.scenario.localization == "drifting" and live("drift time constant (s)"), 60)
    assert live("drift white noise (share)")

    page.get_by_role("tab", name="Method").click()
    ui.pick_option(page, "method", "CBM over time")
    ui.wait_until(lambda: tab.last.settings.method == "cbm-time", 60)
    ui.go_to_frame(page, tab, 20)
    page.get_by_role("tab", name="Steps").click()
    page.get_by_role("button", name="start walkthrough").click()
    for _ in range(9):
        page.get_by_role("button", name="next step ▶").click()
    page.get_by_text(steps.title(9, 10), exact=True).wait_for(timeout=30_000)
    ui.wait_until(lambda: {f"{ROOT}/predicted", f"{ROOT}/measured"} <= tab.controls.walkthrough.nodes.visible_names, 30)
    page.close()
