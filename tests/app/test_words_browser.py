"""Words for people, not for us (issue 39, item 5), in a real browser: the metrics name methods
naturally, CBM without consensus shows no consensus vote, the oracle row says what it is, an
exported recording of one frame says "1 frame", and a frame that cannot run says why without the
error's class name."""
from __future__ import annotations

import pytest

from app.scene.words import error_words
from app.session.explorer import Explorer
from app.session.names import agent_name
from evaluation.trials import NoTrial
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]


@pytest.fixture(scope="module")
def server(small_explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(small_explorer, tmp_path_factory.mktemp("presets")) as running:
        yield running


def rows(page) -> dict[str, str]:
    """The metrics table as row name -> text."""
    return dict(line.split("\t", 1) for line in ui.metrics(page).splitlines() if "\t" in line)


def test_the_metrics_read_naturally(browser, server) -> None:
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    shown = rows(page)
    assert "least squares on the true pairs (oracle)" in shown and not any("limit" in name for name in shown)
    assert "consensus vote" in shown and "matches" in shown
    page.get_by_role("tab", name="Method").click()
    ui.pick_option(page, "method", "CBM without consensus")
    ui.wait_until(lambda: tab.last.settings.method == "cbm-no-consensus" and "CBM without consensus time" in rows(page),
                  60)
    assert "consensus vote" not in rows(page)
    ui.pick_option(page, "method", "none (no calibration)")
    ui.wait_until(lambda: rows(page).get("matches") == "0 (0 right)", 60)
    assert "none (no calibration)" not in ui.metrics(page)
    page.close()


def test_a_recording_of_one_frame_says_one_frame(browser, server, tmp_path) -> None:
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    ui.wait_until(lambda: len(tab.recording) == 1)
    page.get_by_role("tab", name="Explore").click()
    with page.expect_download(timeout=60_000) as download:
        page.get_by_role("button", name="recording of the frames computed (HTML)").click()
    path = tmp_path / "recording.html"
    download.value.save_as(path)
    page.close()
    shown = browser.new_page()
    shown.goto(path.as_uri())
    ui.wait_until(lambda: "recording of 1 frame ·" in shown.locator("#title").inner_text())
    shown.close()


def test_a_frame_that_cannot_run_is_said_in_words(browser, server) -> None:
    page = ui.open_page(browser, server)
    tab = ui.session(server, 1)
    explorer = tab.explorer
    tab.explorer = _NoTrialHere(explorer)
    try:
        tab.apply(lambda s: s.with_params("cbm", sigma1=12.0))
        page.get_by_text("no vehicle stands in for the CAV here").first.wait_for(timeout=30_000)
        assert "NoTrial" not in page.content()
    finally:
        tab.explorer = explorer
    page.close()


def test_errors_keep_their_own_words() -> None:
    assert error_words(NoTrial("frame 3 has one agent")) == "frame 3 has one agent"
    assert "KeyError" in error_words(KeyError("x"))


def test_abstract_agents_and_role_ids_are_named_by_their_role() -> None:
    """SinD's abstract agents have no id ("ego None" was shown); DAIR-V2X's ids repeat the role."""
    assert agent_name("ego", None) == "ego" and agent_name("CAV", None) == "CAV"
    assert agent_name("ego", "vehicle") == "ego" and agent_name("CAV", "infrastructure") == "roadside unit"
    assert agent_name("CAV", "-1", code=True) == "roadside unit `-1`" and agent_name("CAV", "650") == "CAV 650"


class _NoTrialHere:
    """An explorer whose frames make no trial, as a frame with one agent would."""

    def __init__(self, explorer: Explorer) -> None:
        self.inner = explorer

    def __getattr__(self, name: str):
        return getattr(self.inner, name)

    def compute(self, *args):
        raise NoTrial("no vehicle stands in for the CAV here")
