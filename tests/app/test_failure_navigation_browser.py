"""Hunting failures: *next failure* past the last one wraps to the first and says so, *jump to*
shows the frame on screen (not the one picked last), and a pinned baseline's table names the
settings it was pinned under, its matches drawn apart from the missed pairs."""
from __future__ import annotations

import pytest

from app.server import ExplorerServer
from app.session.explorer import Explorer
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]

FAILED = [17, 24]
"""The frames of the synthetic scene that fail under the noisy scenario below (test_timeline_browser)."""


@pytest.fixture(scope="module")
def server(small_explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(small_explorer, tmp_path_factory.mktemp("presets"), protocol="sind",
                            sigma_p=1.0, sigma_theta=10.0) as running:
        yield running


def jump_list(page) -> str:
    """What the *jump to* list shows."""
    return page.locator(f'[id="{ui.label(page, "jump to").get_attribute("for")}"]').input_value()


def shown(tab, frame: int) -> bool:
    return tab.last is not None and tab.last.frame_index == frame and tab.settings.frame == frame


def test_next_failure_wraps_with_a_message_and_jump_to_follows_the_frame(browser, server: ExplorerServer) -> None:
    page = ui.open_first_screen(browser, server)
    tab = ui.session(server, 1)
    page.get_by_role("tab", name="Explore").click()
    page.get_by_role("button", name="run all frames").click()
    ui.wait_until(lambda: len(tab.history.rows) == len(tab.explorer), 180)
    ui.close_notifications(page)
    for frame in (*FAILED, FAILED[0]):
        page.get_by_role("button", name="next failure ▶").click()
        ui.wait_until(lambda f=frame: shown(tab, f), 60)
    page.get_by_text(f"back to the first, frame {FAILED[0]}").first.wait_for(timeout=30_000)
    assert "Past the last failure" in page.locator(".mantine-Notification-root").last.inner_text()
    ui.wait_until(lambda: jump_list(page) == f"frame {FAILED[0]}", 30)
    page.get_by_role("button", name="◀ previous failure").click()
    ui.wait_until(lambda: shown(tab, FAILED[1]), 60)
    page.get_by_text(f"back to the last, frame {FAILED[1]}").first.wait_for(timeout=30_000)

    ui.pick_option(page, "jump to", f"frame {FAILED[0]}")
    ui.wait_until(lambda: shown(tab, FAILED[0]), 60)
    page.get_by_role("button", name="next ▶").click()
    ui.wait_until(lambda: shown(tab, FAILED[0] + 1), 60)
    ui.wait_until(lambda: jump_list(page).startswith("failed frames"), 30)
    page.close()


def test_the_pinned_table_names_the_settings_it_was_pinned_under(browser, server: ExplorerServer) -> None:
    page = ui.open_first_screen(browser, server)
    tab = ui.session(server, 1)
    page.get_by_role("button", name="pin baseline").click()
    page.get_by_text("Pinned under the same settings").first.wait_for(timeout=60_000)
    page.get_by_role("tab", name="Presets").click()
    ui.pick_option(page, "preset", "stress")
    page.get_by_role("button", name="load", exact=True).click()
    ui.wait_until(lambda: tab.last.settings.scenario.sigma_p == 0.9, 60)
    page.get_by_text("Pinned under other settings").first.wait_for(timeout=60_000)
    table = page.get_by_text("Pinned under other settings").first.inner_text()
    assert "position noise σp (m) 1 (now 0.9)" in table and "seed" not in table
    drawn = tab.last_drawing.lines
    assert len(drawn["pinned"].segments) and drawn["pinned"].color != drawn["missed"].color
    page.close()
