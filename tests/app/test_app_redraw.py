"""A redraw in proportion to the change: a sigma edit re-sends the nodes it changed and leaves the
ego's boxes, the map and the CAV's boxes before calibration alone; in a real browser too."""
from __future__ import annotations

import dataclasses
from collections.abc import Callable
from types import SimpleNamespace

import numpy as np
import pytest
import viser

from app.scene.drawing import draw
from app.scene.view import SceneView, fingerprint
from app.server import ExplorerServer
from app.session.explorer import Explorer
from app.session.settings import Settings
from cbm import se2
from cbm.methods import METHODS
from support import browser as ui

STILL = ("ego_boxes", "ego_vehicle", "cav_before", "map_lane_boundary", "map_drivable_area")
"""Nodes that no edit of the method or its parameters changes."""


def _top_down_camera() -> SimpleNamespace:
    """A browser's camera as reported, looking down from 60 m on a 1280x720 window's canvas."""
    return SimpleNamespace(position=(5.0, 0.0, 60.0), look_at=(8.0, 0.0, 0.0), fov=np.radians(50.0),
                           image_width=892, image_height=720, update_timestamp=1.0)


@dataclasses.dataclass
class _Client:
    """What ``SceneView.show`` uses of a browser tab (the camera spreads the labels apart), backed by
    a server without one."""

    scene: viser.SceneApi
    atomic: Callable
    camera: SimpleNamespace = dataclasses.field(default_factory=_top_down_camera)


@pytest.fixture(scope="module")
def viser_server():
    server = viser.ViserServer(port=0, verbose=False)
    yield server
    server.stop()


def test_fingerprint_tells_content_and_style_apart() -> None:
    a = np.arange(12, dtype=np.float32).reshape(2, 2, 3)
    assert fingerprint((a,), (1, 2, 3)) == fingerprint((a.copy(),), (1, 2, 3))
    assert fingerprint((a,), (1, 2, 3)) != fingerprint((a,), (3, 2, 1))
    assert fingerprint((a,), 1) != fingerprint((a + 1,), 1)
    assert fingerprint((a,), 1) != fingerprint((a.reshape(4, 3),), 1)


def test_an_edit_updates_only_the_nodes_it_changes(explorer: Explorer, viser_server: viser.ViserServer) -> None:
    view = SceneView(_Client(viser_server.scene, viser_server.atomic))
    settings = Settings()
    view.show(draw(explorer.compute(settings), explorer.map_segments))
    assert set(view.updates.values()) == {1}, "every node is created once"
    for sigma2 in (2.5, 2.0, 3.0):
        view.show(draw(explorer.compute(settings.with_params("cbm", sigma2=sigma2)), explorer.map_segments))
    assert all(view.updates[name] == 1 for name in STILL)
    view.show(draw(explorer.compute(dataclasses.replace(settings, method="none")), explorer.map_segments))
    assert view.updates["cav_boxes"] == 2, "the CAV's boxes move to where init puts them"
    assert all(view.updates[name] == 1 for name in STILL)


def test_the_map_stays_put_and_its_pose_moves_it_into_the_ego_frame(explorer: Explorer) -> None:
    one, two = (draw(explorer.compute(dataclasses.replace(Settings(), frame=k)), explorer.map_segments)
                for k in (0, 30))
    lines = one.lines["map_lane_boundary"]
    assert fingerprint((lines.segments,)) == fingerprint((two.lines["map_lane_boundary"].segments,))
    outcome = explorer.compute(Settings())
    world = explorer.map_segments["lane_boundary"]
    expected = se2.apply_points(se2.inverse(outcome.trial.ego_pose), world.reshape(-1, 2))
    placed = se2.apply_points(lines.pose, lines.segments[..., :2].reshape(-1, 2).astype(float))
    np.testing.assert_allclose(placed, expected, atol=1e-3)
    assert len(one.lines["map_lane_boundary_2"].segments) == 0, "one copy of the scene, one map"



def test_a_redraw_sets_no_pose_or_label_again_and_ends_where_a_fresh_view_starts(
        explorer: Explorer, viser_server: viser.ViserServer, monkeypatch: pytest.MonkeyPatch) -> None:
    """Poses and labels given again as they were are not set again; a new frame moves them, and
    back on the first frame every node stands and every label reads as a fresh view's do."""
    import app.scene.view as view_module

    placed: list[str] = []
    place = view_module._place
    monkeypatch.setattr(view_module, "_place", lambda handle, pose: (placed.append(handle.name), place(handle, pose)))
    first, other = (draw(explorer.compute(dataclasses.replace(Settings(), frame=k)), explorer.map_segments)
                    for k in (0, 30))
    view = SceneView(_Client(viser_server.scene, viser_server.atomic), root="/redrawn", labels_root="/redrawn_labels")
    view.show(first)
    written = dict(view.written)
    placed.clear()
    view.show(first)
    assert placed == [] and view.written == written
    view.show(other)
    assert "/redrawn/map_lane_boundary" in placed and view.written != written
    view.show(first)
    fresh = SceneView(_Client(viser_server.scene, viser_server.atomic), root="/fresh", labels_root="/fresh_labels")
    fresh.show(first)
    for name, handle in fresh.lines.items():
        np.testing.assert_array_equal(view.lines[name].position, handle.position)
        np.testing.assert_array_equal(view.lines[name].wxyz, handle.wxyz)
    for name, handle in fresh.labels.items():
        mine = view.labels[name]
        assert (mine.text, mine.visible, mine.font_screen_scale) == (handle.text, handle.visible,
                                                                       handle.font_screen_scale)
        np.testing.assert_array_equal(mine.position, handle.position)



def test_geometry_is_reused_by_content_and_a_drawing_is_what_a_fresh_one_is(explorer: Explorer) -> None:
    """``ByContent`` hands out the earlier (read-only) result for arguments of equal content and a new
    one for others; a drawing made after others equals one made with every cache empty."""
    from app.scene import drawing as drawing_module
    from app.scene.geometry import footprint_mesh
    from app.scene.memo import ByContent

    memo, boxes = ByContent(footprint_mesh, kept=2), np.random.default_rng(0).normal(size=(5, 7))
    first = memo(boxes, 0.5)
    assert memo(boxes.copy(), 0.5) is first and not first[0].flags.writeable
    for args in ((boxes + 1, 0.5), (boxes, 0.25)):
        other = memo(*args)
        assert other is not first
        np.testing.assert_array_equal(other[0], footprint_mesh(*args)[0])
    settings = Settings()
    outcomes = [explorer.compute(s) for s in (settings, dataclasses.replace(settings, frame=30),
                                              settings.with_params("cbm", sigma2=2.5))]
    for outcome in (*outcomes, outcomes[0]):
        drawn = draw(outcome, explorer.map_segments)
    for cache in vars(drawing_module).values():
        if isinstance(cache, ByContent):
            cache._results.clear()
    fresh = draw(outcomes[0], explorer.map_segments)
    for name, mesh in fresh.meshes.items():
        np.testing.assert_array_equal(drawn.meshes[name].vertices, mesh.vertices)
        np.testing.assert_array_equal(drawn.meshes[name].faces, mesh.faces)
    for name, lines in fresh.lines.items():
        np.testing.assert_array_equal(drawn.lines[name].segments, lines.segments)


@pytest.fixture(scope="module")
def server(explorer: Explorer, tmp_path_factory: pytest.TempPathFactory):
    with ui.scenario_server(explorer, tmp_path_factory.mktemp("presets")) as running:
        yield running


def _type_into(page, label: str, value: str) -> None:
    row = ui.label(page, label).locator("xpath=ancestor::div[contains(@class, 'mantine-Flex-root')][1]")
    box = row.locator("input.mantine-NumberInput-input")
    box.fill(value)
    box.blur()


@pytest.mark.browser
@ui.requires_chromium
def test_a_sigma2_edit_shows_its_result_and_resends_only_what_changed(browser, server: ExplorerServer) -> None:
    page = ui.open_page(browser, server)
    session = ui.session(server, 1)
    assert "σ2 3.00 m" in ui.metrics(page)
    page.get_by_role("tab", name="Method").click()
    _type_into(page, "σ2 distance (m)", "2.5")
    ui.wait_until(lambda: "σ2 2.50 m" in ui.metrics(page))
    assert session.last.settings.cbm.sigma2 == 2.5
    assert all(session.stage.view.updates[name] == 1 for name in STILL)
    ui.pick_option(page, "method", METHODS["none"].label)
    ui.wait_until(lambda: session.last.settings.method == "none" and "matches\t0 (0 right)" in ui.metrics(page))
    assert session.stage.view.updates["cav_boxes"] == 2 and all(session.stage.view.updates[name] == 1 for name in STILL)
    page.close()
