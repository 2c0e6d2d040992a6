"""Issue 13's fixes without a browser: the diagnosis heading, why a control is disabled, the camera
clear of the panel, the screenshot's panel and the message of a frame CBM cannot run on."""
from __future__ import annotations

import dataclasses
import math

import numpy as np

from app.panels.keynumbers import unusable_markdown
from app.panels.method import inactive_reason
from app.panels.scenario import unread_reason
from app.scene import layouts
from app.scene.text import metrics_markdown
from app.session import export
from app.session.explorer import Explorer
from app.session.settings import Settings
from evaluation.diagnosis import Finding
from evaluation.trials import NoTrial


def test_a_finding_on_a_frame_that_succeeded_is_a_warning(small_explorer: Explorer) -> None:
    outcome = small_explorer.compute(Settings())
    assert outcome.metrics.rte < 1.0 and outcome.metrics.rre < 1.0
    noted = dataclasses.replace(outcome, findings=[Finding("distance_limit", "nearly rejected")])
    assert "**Warnings** (the frame succeeded)" in metrics_markdown(noted)
    assert "Why it failed" not in metrics_markdown(noted)
    failed = dataclasses.replace(noted, metrics=dataclasses.replace(noted.metrics, rte=5.0))
    assert "**Why it failed**" in metrics_markdown(failed)


def test_why_a_method_control_is_disabled() -> None:
    settings = Settings()
    assert inactive_reason(settings, "cbm", "sigma3") is None
    off = settings.with_params("cbm", consensus=False)
    assert inactive_reason(off, "cbm", "sigma3") == "consensus is off"
    icp = dataclasses.replace(settings, method="icp")
    assert inactive_reason(icp, "cbm", "sigma1") == "ICP selected: CBM's parameters do not apply"
    forced = dataclasses.replace(settings, method="cbm-no-consensus")
    assert "forces consensus" in inactive_reason(forced, "cbm", "consensus")


def test_the_simulated_localization_sliders_are_unread_under_the_datasets_own_pose() -> None:
    fixed = Settings().with_scenario(protocol="range", localization="fixed")
    own = fixed.with_scenario(localization="dataset")
    assert unread_reason(fixed, "loc_x") is None and unread_reason(fixed, "sigma_p") is None
    assert all(unread_reason(own, name) == "the dataset's own localization is used"
               for name in ("loc_x", "loc_y", "loc_yaw"))
    assert unread_reason(own, "sigma_p") is None
    assert unread_reason(own, "eta") == "no effect under the range protocol"


def test_the_default_camera_centres_the_layout_on_the_canvas_at_any_pixel_ratio() -> None:
    screen = (math.radians(50.0), 1280 - layouts.PANEL_PX, 720)
    position, look_at = layouts.over_layout((-10.0, 0.0, 60.0), (8.0, 0.0, 0.0), 0.0, screen)
    assert position == (-10.0, 0.0, 60.0) and look_at == (8.0, 0.0, 0.0)
    position, look_at = layouts.over_layout((-10.0, 0.0, 60.0), (8.0, 0.0, 0.0), 30.0, screen)
    assert look_at[1] == position[1] == 30.0
    across = 2 * position[2] * math.tan(screen[0] / 2) * screen[1] / screen[2]
    assert math.isclose(across, 1.25 * 4 * 30.0), "side by side: raised so that both copies fill the canvas"
    for ratio in (0.75, 2.0, 3.0):
        drawn = (screen[0], round(ratio * screen[1]), round(ratio * screen[2]))
        again = layouts.over_layout((-10.0, 0.0, 60.0), (8.0, 0.0, 0.0), 30.0, drawn)
        assert np.allclose(again, (position, look_at), atol=0.05), ratio


def test_the_screenshot_panel_is_the_metrics_as_plain_lines() -> None:
    markdown = "**Frame 3** · ego `a`\n\n| | |\n|---|---|\n| precision / recall | 1.00 / 0.50 |\n\n- " + "x " * 60
    lines = export.panel_lines(markdown)
    assert lines[:3] == ["Frame 3 · ego a", "", "precision / recall: 1.00 / 0.50"]
    assert all(len(line) <= export.WRAP for line in lines) and len(lines) > 4
    image = export.with_panel(np.zeros((200, 300, 4), np.uint8), markdown)
    assert image.shape[1] == 300 + export.PANEL_WIDTH and image.shape[0] >= 200
    assert (image[:, 300 + 4:].sum(axis=-1) < 200).any()


def test_a_frame_of_one_object_says_so() -> None:
    class OneObject:
        track_ids = np.array(["a"])
        categories = np.array(["car"])

    class Sequence(list):
        name = "one"
        warnings: list[str] = []

    lonely = Explorer.__new__(Explorer)
    lonely.sequence = Sequence([OneObject()])
    text = unusable_markdown(lonely, Settings(), NoTrial("no ego and CAV"))
    assert "frame 0 has 1 object(s)" in text and "What to try" in text
