"""Presentation mode and the dark theme without a browser: the palette, the drawing, the camera."""
from __future__ import annotations

import math

import numpy as np

from app.scene import captions, colours, drawing, presentation
from app.session.explorer import Explorer
from app.session.settings import Settings, ViewOptions, from_preset, to_preset


def test_presentation_palette_is_okabe_ito_with_three_distinct_line_styles() -> None:
    assert colours.palette(ViewOptions()) is colours.STANDARD
    shown = colours.palette(ViewOptions(presentation=True))
    assert shown.right.color == (0, 158, 115) and shown.wrong.color == (213, 94, 0)
    assert shown.ego_boxes == (0, 114, 178) and shown.cav_boxes == (230, 159, 0)
    styles = {(s.thickness, s.dash) for s in (shown.right, shown.wrong, shown.missed)}
    assert len(styles) == 3, "right, wrong and missed lines differ by more than colour"
    assert shown.wrong.thickness > shown.right.thickness and shown.wrong.dash and shown.right.dash is None
    assert "Okabe-Ito" in shown.legend and "vermillion" in shown.legend


def test_dark_theme_dims_the_map_and_lightens_the_ego_vehicle() -> None:
    for presentation_mode in (False, True):
        light = colours.palette(ViewOptions(presentation=presentation_mode))
        dark = colours.palette(ViewOptions(presentation=presentation_mode, dark=True))
        assert dark.map != light.map and dark.right == light.right and dark.legend == light.legend
        assert sum(dark.ego_vehicle) > sum(light.ego_vehicle)


def test_presentation_drawing_has_the_palette_large_labels_and_a_caption(explorer: Explorer) -> None:
    plain = drawing.draw(explorer.compute(Settings()), explorer.map_segments)
    outcome = explorer.compute(Settings().with_view(presentation=True, dark=True))
    shown = drawing.draw(outcome, explorer.map_segments)
    assert plain.label_px == 14 and "numbers" not in plain.labels
    assert shown.label_px >= 18
    assert shown.lines["right"].color == (0, 158, 115) and shown.lines["wrong"].thickness == 6.0
    assert shown.meshes["ego_boxes"].color == (0, 114, 178)
    assert shown.lines["map_lane_boundary"].color == colours.DARK_SCENE["map"]["lane_boundary"]
    assert "numbers" not in shown.labels, "the key numbers are a caption beside the scene, not a label in it"
    m = outcome.metrics
    assert captions.caption_lines(outcome) == [f"Frame {outcome.frame_index} · success",
                                               f"precision {m.precision:.2f} · recall {m.recall:.2f}",
                                               f"RTE {m.rte:.2f} m · RRE {m.rre:.2f}°",
                                               "CBM is sure · evidence margin ∞, sure from 8"]
    assert "Frame 0 · success<br>" in captions.caption_html(outcome) and len(shown.agents) == 2


def test_missed_lines_are_dotted_in_presentation_mode(explorer: Explorer) -> None:
    tight = Settings().with_params("cbm", sigma2=0.25, sigma3=0.25, sigma1=1.0).with_scenario(sigma_p=0.8,
                                                                                              sigma_theta=10.0)
    plain = drawing.draw(explorer.compute(tight), {})
    shown = drawing.draw(explorer.compute(tight.with_view(presentation=True)), {})
    missed = plain.lines["missed"].segments
    assert len(missed) > 0
    assert len(shown.lines["missed"].segments) > 2 * len(missed), "shorter dashes: more of them"


def test_camera_over_the_agents_frames_both() -> None:
    agents = ((0.0, 0.0), (30.0, -20.0))
    fov = math.radians(50)
    position, look_at = presentation.camera_over(agents, fov)
    assert look_at[1] == -10.0 and position[2] >= presentation.LOWEST
    half_view = position[2] * math.tan(fov / 2)
    centre = np.array(look_at[:2])
    assert all(np.max(np.abs(np.array(a) - centre)) < half_view for a in agents)
    assert position[0] < look_at[0], "a little behind, so x points up the screen"


def test_presets_keep_presentation_and_dark() -> None:
    settings = Settings().with_view(presentation=True, dark=True)
    assert to_preset(settings)["view"]["presentation"] is True
    assert from_preset(to_preset(settings)).view == settings.view
