"""Issue 50, item 1 in a real browser: user text (a preset's name and description, a dataset's
categories) reaches the page as text, never as elements or scripts, in any tab."""
from __future__ import annotations

from pathlib import Path

import pytest

import loaders
from app.session.explorer import Explorer
from support import browser as ui

pytestmark = [pytest.mark.browser, ui.requires_chromium]

IFRAME = '<iframe srcdoc="<script>parent.document.title=1337</script>">'
INJECTED = "iframe, #pwn1, #pwn2, #pwn3, #pwn4"
"""What the hostile strings below would add to the page if they were read as HTML."""


def _nothing_injected(page) -> None:
    assert page.title() == "CBM Explorer"
    assert page.evaluate("() => window.pwned") is None
    assert page.locator(INJECTED).count() == 0


def tab_of(server, count: int):
    return ui.session(server, count)


def test_a_hostile_preset_name_and_description_are_shown_as_text_in_another_tab(browser, tmp_path: Path) -> None:
    presets = tmp_path / "presets"
    presets.mkdir()
    (presets / "bold.toml").write_text(
        "description = \"<b id=pwn1>..<img id=pwn2 src=x onerror='window.pwned=2'>\"\nname = \"<b id=pwn3>x</b>\"\n")
    with ui.scenario_server(Explorer(loaders.open("synthetic:8")), presets) as server:
        first = ui.open_page(browser, server)
        tab = ui.session(server, 1)
        first.get_by_role("tab", name="Presets").click()
        row = ui.label(first, "save as").locator("xpath=ancestor::div[contains(@class, 'mantine-Flex-root')][1]")
        box = row.locator("input").first
        box.fill(IFRAME)
        box.blur()
        ui.wait_until(lambda: tab.controls.presets.name.value == IFRAME)
        first.get_by_role("button", name="save current settings").click()
        ui.wait_until(lambda: len(list(presets.glob("*.toml"))) == 2, 30)
        saved = next(p.stem for p in presets.glob("*.toml") if p.name != "bold.toml")
        second = ui.open_page(browser, server)
        second.get_by_role("tab", name="Presets").click()
        ui.pick_option(second, "preset", saved)
        about = second.get_by_text("Saved from CBM Explorer as").first
        about.wait_for(timeout=30_000)
        _nothing_injected(second)
        assert about.inner_text() == f"Saved from CBM Explorer as '{IFRAME}'."
        ui.pick_option(second, "preset", "bold")
        ui.wait_until(lambda: "pwn1" in tab_of(server, 2).controls.presets.about.content, 30)
        _nothing_injected(second)
        second.get_by_text("<b id=pwn1>..<img id=pwn2 src=x onerror='window.pwned=2'>").first.wait_for(timeout=30_000)
        _nothing_injected(second)
        _nothing_injected(first)
        first.close()
        second.close()


def test_a_hostile_category_in_a_dataset_is_shown_as_text(browser, tmp_path: Path) -> None:
    category = "<img id=pwn4 src=x onerror='window.pwned=4'>"
    path = tmp_path / "one.csv"
    path.write_text("frame,track_id,category,x,y,length,width,yaw\n"
                    + "".join(f'{frame},p{k},"{category}",{frame}.0,{3 * k}.0,0.5,0.5,0.0\n'
                              for frame in range(3) for k in range(4)))
    with ui.scenario_server(Explorer(loaders.open(str(path))), tmp_path / "presets") as server:
        page = ui.address(server)
        tab = browser.new_page(viewport={"width": 1400, "height": 900})
        tab.goto(page)
        tab.get_by_text("What is missing").first.wait_for(timeout=90_000)
        _nothing_injected(tab)
        assert category in tab.get_by_text("What is missing").first.inner_text()
        tab.close()
