"""What a newcomer sees first, in a real browser at 1280x720 on the shipped scene: the frame controls
in the first screen and the tabs on one row (issue 24, item 6), controls labelled in words (item 7),
and only what can work on this dataset offered, the rest disabled with the reason (item 8); fewer
CAVs than the pose graph needs switch the method to CBM and say so (issue 39, item 7)."""
from __future__ import annotations

import re

import pytest

from app.session.explorer import Explorer
from cbm.methods import METHODS
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]

GRAPH = METHODS["cbm-graph"].label


@pytest.fixture(scope="module")
def server(explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(explorer, tmp_path_factory.mktemp("presets")) as running:
        yield running


def slider_labels(page) -> list[str]:
    """The labels of every slider on the page, in every tab of the panel (each slider once)."""
    found: dict[str, str] = {}
    for tab in ui.panel_tabs(page):
        tab.click()
        for label in page.locator("label").all():
            control = label.get_attribute("for")
            if control and label.is_visible() and page.locator(f'[id="{control}"] [role="slider"]').count():
                found[control] = label.inner_text()
    return list(found.values())


def options_of(page, text: str) -> list[str]:
    """The options a dropdown offers (opened, read, closed)."""
    page.locator(f'[id="{ui.label(page, text).get_attribute("for")}"]').click()
    page.get_by_role("option").first.wait_for(timeout=10_000)
    names = [option.inner_text() for option in page.get_by_role("option").all()]
    page.keyboard.press("Escape")
    return names


def disabled(page, text: str) -> bool:
    return page.locator(f'[id="{ui.label(page, text).get_attribute("for")}"]').is_disabled()


def test_the_frame_slider_and_play_are_in_the_first_screen_and_the_tabs_on_one_row(browser, server) -> None:
    page = ui.open_first_screen(browser, server)
    tab = ui.session(server, 1)
    assert ui.in_first_screen(ui.slider(page, "frame"))
    play = page.get_by_role("button", name="▶ play")
    assert ui.in_first_screen(play) and ui.in_first_screen(page.get_by_role("button", name="next ▶"))
    tabs = ui.panel_tabs(page)
    assert len(tabs) == 6 and len({round(t.bounding_box()["y"]) for t in tabs}) == 1
    assert [name for name in slider_labels(page) if re.search(r"\bframe\b", name)] == ["frame"]

    start = tab.settings.frame
    play.click()
    ui.wait_until(lambda: tab.last.frame_index >= start + 2, 60)
    page.get_by_role("button", name="❚❚ pause").click()
    page.get_by_role("button", name="▶ play").wait_for(timeout=10_000)
    stopped = tab.settings.frame
    ui.wait_until(lambda: tab.last.frame_index == stopped, 60)
    assert tab.settings.frame == stopped
    page.close()


def test_every_control_is_labelled_in_words_and_the_page_is_named(browser, server) -> None:
    page = ui.open_first_screen(browser, server)
    tab = ui.session(server, 1)
    ui.wait_until(lambda: page.title() == "CBM Explorer")
    assert not re.search(r"\bego\s+ego\b", ui.header(page)), ui.header(page)
    page.get_by_role("tab", name="Method").click()
    for label, name in [(m.label, m.name) for m in METHODS.values() if not (m.takes_peers or m.offline)]:
        ui.pick_option(page, "method", label)
        ui.wait_until(lambda n=name: tab.settings.method == n)
        shown = [lab.inner_text() for lab in page.locator("label").all() if lab.is_visible()]
        assert shown and not [text for text in shown if "_" in text], (name, shown)
    assert ui.label(page, "consensus rule").is_visible() and ui.label(page, "Welsch scale floor (m)").is_visible()
    ui.pick_option(page, "method", "CBM")
    page.get_by_text("σ1 and σ2: how alike two objects' neighbourhoods must be to match").first.wait_for(
        timeout=10_000)
    ui.slider(page, "σ2 distance (m)").hover()
    page.get_by_text(re.compile(r"their tips are at most this far apart, \|Δx\| \+ \|Δy\|")).first.wait_for(
        timeout=10_000)
    ui.slider(page, "σ3 voting (m)").hover()
    page.get_by_text(re.compile(r"In the consensus vote, a candidate pair backs another")).first.wait_for(
        timeout=10_000)
    page.close()


def test_a_preset_says_what_it_is_before_loading_and_default_resets_the_view(browser, server) -> None:
    page = ui.open_first_screen(browser, server)
    tab = ui.session(server, 1)
    page.get_by_role("tab", name="Presets").click()
    ui.pick_option(page, "preset", "teaching")
    page.get_by_text("For a first look: perfect detections").first.wait_for(timeout=10_000)
    assert tab.settings.scenario.sigma_p == 0.2, "picking a preset does not load it"
    page.get_by_role("button", name="load").click()
    ui.wait_until(lambda: tab.last.settings.view.layout == "side by side" and tab.last.settings.view.ghosts, 60)
    ui.pick_option(page, "preset", "default")
    page.get_by_text("The app's defaults").first.wait_for(timeout=10_000)
    page.get_by_role("button", name="load").click()
    ui.wait_until(lambda: tab.last.settings.scenario.sigma_p == 0.2, 60)
    view = tab.last.settings.view
    assert (view.layout, view.ghosts, view.lines, view.labels) == ("overlay", False, True, True)
    page.close()


def test_what_this_dataset_cannot_do_is_disabled_with_the_reason(browser, server) -> None:
    page = ui.open_first_screen(browser, server)
    tab = ui.session(server, 1)
    page.get_by_role("tab", name="View").click()
    assert disabled(page, "LiDAR points")
    page.get_by_text("this dataset ships no LiDAR points").first.wait_for(timeout=10_000)

    page.get_by_role("tab", name="Scenario").click()
    assert "dataset" not in options_of(page, "localization error")
    assert {"fixed", "gaussian"} <= set(options_of(page, "localization error"))
    page.get_by_text("this dataset reports no noisy CAV poses of its own").first.wait_for(timeout=10_000)

    page.get_by_role("tab", name="Method").click()
    assert GRAPH not in options_of(page, "method")
    page.get_by_text(f"Not offered: {GRAPH}").first.wait_for(timeout=10_000)
    cavs = page.locator(f'[id="{ui.label(page, "CAVs").get_attribute("for")}"]')
    cavs.fill("3")
    cavs.blur()
    ui.wait_until(lambda: tab.last.settings.cavs == 3, 60)
    ui.wait_until(lambda: GRAPH in options_of(page, "method"))
    ui.pick_option(page, "method", GRAPH)
    ui.wait_until(lambda: tab.last.settings.method == "cbm-graph", 60)
    cavs.fill("1")
    cavs.blur()
    page.get_by_text("Method switched").first.wait_for(timeout=20_000)
    page.get_by_text(f"{GRAPH} needs 2 CAVs or more, so with 1 CAV the method is now CBM").first.wait_for(
        timeout=20_000)
    ui.wait_until(lambda: tab.last.settings.cavs == 1 and tab.last.settings.method == "cbm", 60)
    ui.wait_until(lambda: page.locator(f'[id="{ui.label(page, "method").get_attribute("for")}"]').input_value()
                  == METHODS["cbm"].label)
    assert cavs.input_value() == "1"
    assert page.get_by_text("CBM cannot run on this frame").count() == 0
    assert page.get_by_text("Setting refused").count() == 0
    page.close()

