"""Real-browser tests of what the accuracy work shows a user: CBM's own pairs against the refined ones
in the scene, and the reference methods in the method list."""
from __future__ import annotations

import numpy as np
import pytest

from app.server import ExplorerServer
from app.session.explorer import Explorer
from support import browser as ui

pytestmark = [pytest.mark.browser,
              ui.requires_chromium]


@pytest.fixture(scope="module")
def hard_server(explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    """The shipped scene under hard noise (SIND protocol, eta 0.3, 0.6 m, 10 degrees): CBM's own
    sets miss many true pairs there and the re-association adds them."""
    with ui.scenario_server(explorer, tmp_path_factory.mktemp("presets"), protocol="sind", eta=0.3, sigma_p=0.6,
                            sigma_theta=10.0, seed=1) as running:
        yield running


def drawn_pairs(tab) -> int:
    """Match lines drawn for right and wrong pairs (each pair one segment; hidden nodes hold none)."""
    lines = tab.stage.view.lines
    return sum(len(lines[name].points) for name in ("right", "wrong") if lines[name].visible)


def test_cbm_lines_switch_between_own_and_refined_pairs(browser, hard_server: ExplorerServer) -> None:
    page = ui.open_page(browser, hard_server)
    tab = ui.session(hard_server, 1)
    result = tab.last.result
    assert len(result.pairs) > len(result.context_pairs), "the re-association added pairs on this frame"
    assert f"CBM's own {len(result.context_pairs)}" in ui.metrics(page)
    assert drawn_pairs(tab) == len(result.pairs)

    page.get_by_role("tab", name="View").click()
    ui.pick_option(page, "CBM's lines", "CBM's own pairs")
    ui.wait_until(lambda: tab.last.settings.view.line_pairs == "own" and drawn_pairs(tab) == len(result.context_pairs))
    np.testing.assert_array_equal(tab.last.result.context_pairs, result.context_pairs)

    ui.pick_option(page, "CBM's lines", "all pairs (after refinement)")
    ui.wait_until(lambda: tab.last.settings.view.line_pairs == "refined" and drawn_pairs(tab) == len(result.pairs))
    page.close()


def test_reference_methods_in_the_method_list(browser, hard_server: ExplorerServer) -> None:
    page = ui.open_page(browser, hard_server)
    tab = ui.session(hard_server, 1)
    assert "least squares on the true pairs (oracle)" in ui.metrics(page)
    page.get_by_role("tab", name="Method").click()

    ui.pick_option(page, "method", "oracle (least squares on the true pairs)")
    ui.wait_until(lambda: tab.last.settings.method == "oracle")
    ui.wait_until(lambda: "1.00 / 1.00" in ui.metrics(page))
    assert tab.last.metrics.rte == tab.last.limit.rte
    assert not page.get_by_text("CBM's lines").is_visible()

    ui.pick_option(page, "method", "none (no calibration)")
    ui.wait_until(lambda: "matches\t0 (0 right)" in ui.metrics(page))
    rows = dict(line.split("\t") for line in ui.metrics(page).splitlines() if "\t" in line)
    assert rows["RRE / RTE"] == rows["before calibration"]
    page.close()
