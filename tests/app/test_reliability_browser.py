"""Issue 16 in a real browser: a dataset CBM cannot run on gets a lasting message (started through
the command line), and the Presets tab lists the preset files it skipped and refuses a name that
would overwrite another preset's file; issue 27: a name in another script keeps its letters."""
from __future__ import annotations

import signal
from pathlib import Path

import pytest

import loaders
from app.session.explorer import Explorer
from support import browser as ui

from .test_reliability_cli import serving

pytestmark = [pytest.mark.browser, ui.requires_chromium]


def _one_object(folder: Path) -> str:
    path = folder / "one.csv"
    path.write_text("frame,track_id,category,x,y,length,width,yaw\n"
                    + "".join(f"{frame},car1,vehicle,{frame}.0,0.0,4.5,1.9,0.0\n" for frame in range(3)))
    return str(path)


@pytest.mark.parametrize("dataset, words", [("synthetic:0", "has 0 object(s)"), ("synthetic:1", "has 1 object(s)"),
                                            ("one-object", "has 1 object(s)")])
def test_a_dataset_cbm_cannot_run_on_says_so_and_the_app_keeps_working(browser, tmp_path: Path, dataset: str,
                                                                       words: str) -> None:
    name = _one_object(tmp_path) if dataset == "one-object" else dataset
    with serving("--dataset", name, "--port", "0", presets=tmp_path / "presets") as (process, url):
        page = browser.new_page(viewport={"width": 1280, "height": 800})
        page.goto(url)
        page.get_by_text("CBM cannot run on this frame.").first.wait_for(timeout=90_000)
        assert words in page.get_by_text("What is missing").first.inner_text()
        assert "CBM cannot run" in page.locator("#cbm-key-numbers").inner_text()
        assert page.get_by_text("Computing the first frame…").count() == 0
        page.get_by_role("tab", name="Presets").click()
        page.get_by_role("button", name="save current settings").wait_for(timeout=30_000)
        page.close()
        process.send_signal(signal.SIGTERM)
        process.wait(timeout=10)
        assert process.returncode == 0 and "CBM cannot run; the page says what is missing" in process.stderr.read()


def test_presets_tab_lists_skipped_files_and_refuses_a_colliding_name(browser, tmp_path: Path) -> None:
    presets = tmp_path / "presets"
    presets.mkdir()
    (presets / "deep.toml").write_text("x = " + "[" * 3000 + "]" * 3000 + "\n")
    (presets / "huge.toml").write_text("# " + "a" * 300_000 + "\n")
    (presets / "latin1.toml").write_bytes(b'description = "caf\xe9"\n')
    with ui.scenario_server(Explorer(loaders.open("synthetic:8")), presets) as server:
        page = ui.open_page(browser, server)
        tab = ui.session(server, 1)
        page.get_by_role("tab", name="Presets").click()
        listing = page.get_by_text("Preset files skipped").first.locator("xpath=ancestor::div[1]")
        listing.wait_for(timeout=30_000)
        for words in ("deep.toml: nested deeper than", "huge.toml: larger than 256 KB", "latin1.toml"):
            page.get_by_text(words).first.wait_for(timeout=30_000)
        ui.close_notifications(page)
        row = ui.label(page, "save as").locator("xpath=ancestor::div[contains(@class, 'mantine-Flex-root')][1]")
        name = row.locator("input").first
        for typed in ("../x", "..\\x"):
            name.fill(typed)
            name.blur()
            ui.wait_until(lambda typed=typed: tab.controls.presets.name.value == typed)
            page.get_by_role("button", name="save current settings").click()
        page.get_by_text("which holds the preset '../x'").first.wait_for(timeout=30_000)
        assert [p.name for p in presets.glob("x*.toml")] == ["x.toml"]
        assert 'name = "../x"' in (presets / "x.toml").read_text()
        page.close()


def test_a_preset_named_in_another_script_is_saved_under_its_own_letters(browser, tmp_path: Path) -> None:
    """Issue 27, row 13: "配置 2" is saved as 配置-2.toml (was: 2.toml) and offered under that name."""
    presets = tmp_path / "presets"
    presets.mkdir()
    with ui.scenario_server(Explorer(loaders.open("synthetic:8")), presets) as server:
        page = ui.open_page(browser, server)
        tab = ui.session(server, 1)
        page.get_by_role("tab", name="Presets").click()
        row = ui.label(page, "save as").locator("xpath=ancestor::div[contains(@class, 'mantine-Flex-root')][1]")
        name = row.locator("input").first
        name.fill("配置 2")
        name.blur()
        ui.wait_until(lambda: tab.controls.presets.name.value == "配置 2")
        page.get_by_role("button", name="save current settings").click()
        page.get_by_text("配置 2 -> 配置-2.toml").first.wait_for(timeout=30_000)
        assert [p.name for p in presets.iterdir()] == ["配置-2.toml"]
        assert "配置-2" in tab.controls.presets.presets and 'name = "配置 2"' in (presets / "配置-2.toml").read_text()
        page.close()
