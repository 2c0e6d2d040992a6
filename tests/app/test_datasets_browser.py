"""Open data from the page in a browser (issue 47, item 5): the dataset picker lists the shipped scene
and the datasets under the folders named at start, and nothing outside them; a pick switches the
tab without a restart, on the first frame CBM can run on, saying so; tabs on one dataset share its
explorer; a dataset that does not load is named and the tab stays."""
from __future__ import annotations

import pytest

import loaders
from app.server import ExplorerServer
from app.session.datasets import Catalogue, data_roots, start_dataset
from app.session.explorer import Explorer
from app.session.settings import Settings
from support import browser as ui
from support.recordings import intersection

pytestmark = [pytest.mark.browser, ui.requires_chromium]


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory):
    base = tmp_path_factory.mktemp("picker")
    data = base / "data"
    intersection(data / "crossing")
    (data / "broken").mkdir()
    (data / "broken" / "vehicle_tracks_000.csv").write_text("track_id,frame_id\n1,not a number\n")
    intersection(base / "elsewhere")
    (data / "elsewhere").symlink_to(base / "elsewhere")
    explorer = Explorer(loaders.open("synthetic:60"))
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("CBM_EXPLORER_PRESETS", str(base / "presets"))
        running = ExplorerServer(explorer, Settings(), port=0,
                                 catalogue=Catalogue(start_dataset("synthetic:60"), explorer, data_roots([data])))
        yield running
        running.stop()


def session_of(server: ExplorerServer, page_count: int):
    ui.wait_until(lambda: len(server.sessions) == page_count, 60)
    return max(server.sessions.items())[1]


def options(page) -> list[str]:
    control = ui.label(page, "dataset").get_attribute("for")
    page.locator(f'[id="{control}"]').click()
    found = [option.inner_text() for option in page.get_by_role("option").all()]
    page.keyboard.press("Escape")
    return found


def test_a_picked_dataset_opens_in_the_tab_on_the_first_frame_cbm_can_run_on(browser, server: ExplorerServer) -> None:
    page = ui.open_page(browser, server)
    first = ui.session(server, 1)
    ui.close_notifications(page)
    assert options(page) == ["synthetic:60", "argoverse2 (shipped)", "data/broken", "data/crossing"]
    client = first.client.client_id
    ui.pick_option(page, "dataset", "data/crossing")
    crossing = server.catalogue.explorer("data/crossing")
    ui.wait_until(lambda: server.sessions.get(client) not in (None, first)
                  and server.sessions[client].explorer is crossing and server.sessions[client].last is not None, 120)
    tab = server.sessions[client]
    assert tab.last.frame_index == 10
    ui.wait_until(lambda: ui.header(page) == "Frame 10", 60)
    page.get_by_text("Starting on frame 10").first.wait_for(timeout=30_000)
    page.get_by_text("frame 10, the first with enough, is shown").first.wait_for(timeout=30_000)
    assert first.worker.superseded and len(server.sessions) == 1

    other = ui.open_page(browser, server)
    second = session_of(server, 2)
    ui.pick_option(other, "dataset", "data/crossing")
    ui.wait_until(lambda: server.sessions.get(second.client.client_id) not in (None, second), 120)
    assert server.sessions[second.client.client_id].explorer is crossing
    other.close()
    page.close()


def test_a_dataset_that_does_not_load_is_named_and_the_tab_stays(browser, server: ExplorerServer) -> None:
    page = ui.open_page(browser, server)
    tab = session_of(server, 1)
    ui.close_notifications(page)
    ui.pick_option(page, "dataset", "data/broken")
    page.get_by_text("data/broken not opened").first.wait_for(timeout=60_000)
    assert server.sessions[tab.client.client_id] is tab and tab.explorer is server.explorer
    ui.wait_until(lambda: ui.label(page, "dataset").count() == 1 and
                  page.locator(f'[id="{ui.label(page, "dataset").get_attribute("for")}"]').input_value()
                  == "synthetic:60", 30)
    page.close()
