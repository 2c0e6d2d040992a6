"""Speed a user feels, in a browser (issue 47, item 7): while a method computes the key numbers say
so instead of the verdict on screen; FreeAlign waits for its compiled kernels saying so; play shows
every frame and says how fast it goes when it cannot keep up; a CSV export takes the frames computed
already."""
from __future__ import annotations

import csv
import io
import threading

import pytest

from app.server import ExplorerServer
from app.session import sequence
from app.session.explorer import Explorer
from app.session.kernels import BASELINES
from app.session.over_time import Runs
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]


@pytest.fixture(scope="module")
def server(small_explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(small_explorer, tmp_path_factory.mktemp("presets"), protocol="sind", sigma_p=0.3,
                            sigma_theta=3.0, seed=31) as running:
        yield running


def key_numbers(page) -> str:
    return page.locator("#cbm-key-numbers").inner_text()


class HeldBaselines:
    """The server's kernels, but the baselines' held until ``released``."""

    def __init__(self, real) -> None:
        self.real, self.released = real, threading.Event()

    def __getattr__(self, name: str):
        return getattr(self.real, name)

    def ready_for(self, method: str) -> bool:
        return self.real.ready_for(method) and (method not in BASELINES or self.released.is_set())

    def wait(self, timeout: float | None = None, method: str = "cbm") -> bool:
        return self.released.wait(timeout) if method in BASELINES else self.real.wait(timeout, method)


def test_the_key_numbers_say_which_method_computes_instead_of_the_last_verdict(browser, server: ExplorerServer,
                                                                               monkeypatch) -> None:
    explorer, held, entered = server.explorer, threading.Event(), threading.Event()
    compute = explorer.compute

    def slow_icp(settings, *args, **kwargs):
        if settings.method == "icp":
            entered.set()
            held.wait(60)
        return compute(settings, *args, **kwargs)

    monkeypatch.setattr(explorer, "compute", slow_icp)
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    ui.close_notifications(page)
    assert "success" in key_numbers(page) or "failed" in key_numbers(page)
    page.get_by_role("tab", name="Method").click()
    ui.pick_option(page, "method", "ICP")
    assert entered.wait(60)
    ui.wait_until(lambda: f"ICP computing frame {tab.settings.frame}" in key_numbers(page), 30)
    assert "success" not in key_numbers(page) and "failed" not in key_numbers(page)
    held.set()
    ui.wait_until(lambda: tab.last.settings.method == "icp", 60)
    ui.wait_until(lambda: "computing" not in key_numbers(page) and ("success" in key_numbers(page) or
                                                                    "failed" in key_numbers(page)), 30)
    page.close()


def test_freealign_waits_for_its_kernels_saying_so(browser, server: ExplorerServer, monkeypatch) -> None:
    kernels = HeldBaselines(server.kernels)
    monkeypatch.setattr(server, "kernels", kernels)
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    ui.close_notifications(page)
    page.get_by_role("tab", name="Method").click()
    ui.pick_option(page, "method", "FreeAlign")
    page.get_by_text("Preparing FreeAlign's compiled kernels").first.wait_for(timeout=30_000)
    assert "FreeAlign computing frame" in key_numbers(page) and tab.last.settings.method == "cbm"
    kernels.released.set()
    ui.wait_until(lambda: tab.last.settings.method == "freealign", 120)
    page.close()


def test_play_shows_every_frame_and_says_how_fast_it_goes_when_it_cannot_keep_up(browser, server: ExplorerServer,
                                                                                  monkeypatch) -> None:
    """Each frame takes half a second here (4 frames/s asked): none is skipped, and the status line
    gives the rate reached."""
    explorer, compute = server.explorer, server.explorer.compute

    def slow(settings, *args, **kwargs):
        outcome = compute(settings, *args, **kwargs)
        threading.Event().wait(0.5)
        return outcome

    monkeypatch.setattr(explorer, "compute", slow)
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    ui.close_notifications(page)
    shown, add = [], tab.recording.add
    monkeypatch.setattr(tab.recording, "add", lambda outcome: shown.append(outcome.frame_index) or add(outcome))
    page.get_by_role("button", name="▶ play").click()
    page.get_by_text("of the 4 asked: every frame is shown").first.wait_for(timeout=60_000)
    ui.wait_until(lambda: len(shown) >= 5, 60)
    page.get_by_role("button", name="❚❚ pause").click()
    ui.wait_until(lambda: not tab.worker.superseded, 30)
    assert shown[:5] == list(range(shown[0], shown[0] + 5))
    page.close()


def _csv_rows(download, tmp_path) -> list[dict]:
    path = tmp_path / "rows.csv"
    download.save_as(path)
    return list(csv.DictReader(io.StringIO(path.read_text())))


def test_a_csv_export_takes_the_frames_a_comparison_and_cbm_over_time_computed(browser, server: ExplorerServer,
                                                                                 monkeypatch, tmp_path) -> None:
    """After a comparison, CBM's CSV runs no frame; after a jump to frame 20 under CBM over time,
    the CSV computes frames 21 on only."""
    server.explorer.rows.clear()
    ran, run = [], sequence.run
    monkeypatch.setattr(sequence, "run",
                        lambda sweep, inputs: ran.extend(i.index for i in inputs) or run(sweep, inputs))
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    ui.close_notifications(page)
    page.get_by_role("tab", name="Explore").click()
    page.get_by_text("Every method, whole sequence", exact=True).click()
    over_time = page.locator(f'[id="{ui.label(page, "CBM over time").get_attribute("for")}"]')
    over_time.click()
    ui.wait_until(lambda: not tab.controls.compare.ticks["cbm-time"].value)
    page.get_by_role("button", name="run every method ticked").click()
    ui.wait_until(lambda: tab.controls.compare.comparison is not None, 300)
    compared = [row["rte"] for row in tab.controls.compare.comparison.runs["cbm"].rows]
    ran.clear()
    with page.expect_download(timeout=120_000) as download:
        page.get_by_role("button", name="per-frame metrics (CSV)").click()
    rows = _csv_rows(download.value, tmp_path)
    assert ran == [] and [float(row["rte"]) for row in rows] == pytest.approx(compared)

    steps, step = [], Runs._step
    monkeypatch.setattr(Runs, "_step", staticmethod(lambda run, settings, j, trial_of: steps.append(j) or
                                                    step(run, settings, j, trial_of)))
    page.get_by_role("tab", name="Method").click()
    ui.pick_option(page, "method", "CBM over time")
    ui.go_to_frame(page, tab, 20)
    assert steps == list(range(21))
    page.get_by_role("tab", name="Explore").click()
    with page.expect_download(timeout=120_000) as download:
        page.get_by_role("button", name="per-frame metrics (CSV)").click()
    rows = _csv_rows(download.value, tmp_path)
    assert steps == list(range(len(tab.explorer))) and len(rows) == len(tab.explorer)
    assert {row["method"] for row in rows} == {"cbm-time"}
    page.close()
