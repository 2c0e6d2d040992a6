"""One settings value per tab, changed in one place: a preset or a step moves every control and
recomputes once (the app's own updates of controls do not fire further changes)."""
from __future__ import annotations

import time

import pytest

from app.server import ExplorerServer
from app.session.explorer import Explorer
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]


@pytest.fixture(scope="module")
def server(small_explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(small_explorer, tmp_path_factory.mktemp("presets"), protocol="sind") as running:
        yield running


def count_calls(owner, name: str):
    """Count the calls of ``owner.name`` from now on (the counter is the returned list's length)."""
    calls, original = [], getattr(owner, name)

    def counted(*args, **kwargs):
        calls.append(args)
        return original(*args, **kwargs)

    setattr(owner, name, counted)
    return calls


def test_a_preset_moves_every_control_and_recomputes_once(browser, server: ExplorerServer) -> None:
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    page.get_by_role("tab", name="Presets").click()
    ui.pick_option(page, "preset", "teaching")
    applied, submitted = count_calls(tab, "apply"), count_calls(tab.worker, "submit")
    ui.pick_option(page, "preset", "stress")
    page.get_by_role("button", name="load", exact=True).click()
    ui.wait_until(lambda: tab.settings.scenario.sigma_p == 0.9 and tab.last.settings == tab.settings)
    time.sleep(0.5)
    assert len(applied) == 1 and len(submitted) == 1
    page.get_by_role("tab", name="Scenario").click()
    assert ui.slider(page, "position noise σp (m)").get_attribute("aria-valuenow") == "0.9"
    assert ui.slider(page, "co-visibility eta").get_attribute("aria-valuenow") == "0.25"
    page.close()


def test_a_step_advances_one_frame_with_one_recompute(browser, server: ExplorerServer) -> None:
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    ui.wait_until(lambda: tab.last is not None)
    applied, submitted = count_calls(tab, "apply"), count_calls(tab.worker, "submit")
    start = tab.settings.frame
    page.get_by_role("button", name="next ▶").click()
    ui.wait_until(lambda: tab.last.frame_index == start + 1)
    time.sleep(0.5)
    assert len(applied) == 1 and len(submitted) == 1 and tab.settings.frame == start + 1
    assert ui.slider(page, "frame").get_attribute("aria-valuenow") == str(start + 1)
    page.close()


def test_only_the_parameters_that_act_are_live(browser, server: ExplorerServer) -> None:
    """A parameter that has no effect stays in view, disabled (issue 13); another method's set hides."""
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    page.get_by_role("tab", name="Method").click()

    def live(text: str) -> bool:
        control = page.locator(f'[id="{ui.label(page, text).get_attribute("for")}"]')
        handle = control.locator('[role="slider"]')
        if handle.count():
            return handle.first.get_attribute("data-disabled") != "true"
        return control.is_enabled()

    assert live("σ3 voting (m)")
    ui.pick_option(page, "method", "CBM without consensus")
    ui.wait_until(lambda: tab.settings.method == "cbm-no-consensus" and not live("σ3 voting (m)"))
    assert not live("consensus") and live("σ1 angle (°)")
    ui.pick_option(page, "method", "ICP")
    ui.wait_until(lambda: not live("σ1 angle (°)"))
    assert ui.label(page, "most iterations").is_visible()
    ui.pick_option(page, "method", "CBM")
    ui.wait_until(lambda: live("σ3 voting (m)") and not ui.label(page, "most iterations").is_visible())
    page.close()
