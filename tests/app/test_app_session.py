"""Session logic without a browser: settings -> recompute -> what would be drawn."""
from __future__ import annotations

import dataclasses
import threading

import numpy as np
import pytest

import loaders
from app.scene import cavs, drawing, picking
from app.session.coalesce import Coalescer
from app.session.explorer import Explorer
from app.session.settings import AUTO_CAV, Settings, ViewOptions
from cbm import se2
from evaluation.trials import sequence_cav


def _view(settings: Settings, **changes) -> Settings:
    return dataclasses.replace(settings, view=dataclasses.replace(settings.view, **changes))


def test_default_frame_is_repaired_and_drawn(explorer: Explorer) -> None:
    outcome = explorer.compute(Settings())
    picture = drawing.draw(outcome, explorer.map_segments)
    m = outcome.metrics
    assert outcome.ego_id == "ego" and outcome.cav_id == sequence_cav(explorer.sequence)
    assert m.n_ego > 10 and m.n_cav > 10 and m.n_true > 5
    assert m.precision == 1.0 and m.rte < 0.5 and m.rre < 1.0
    assert {"ego_boxes", "cav_boxes", "ego_vehicle", "cav_vehicle"} <= set(picture.meshes)
    assert {"right", "wrong", "missed", "ghosts", "cav_before", "map_lane_boundary"} <= set(picture.lines)
    assert len(picture.meshes["ego_boxes"].faces) == 2 * m.n_ego, "a box is its top face: two triangles"
    assert len(picture.meshes["cav_boxes"].faces) == 2 * m.n_cav
    assert len(picture.lines["cav_before"].segments) == 4 * m.n_cav, "the CAV's boxes at init: outlines"
    assert len(picture.lines["right"].segments) == m.n_correct
    assert len(picture.lines["wrong"].segments) == m.n_matched - m.n_correct
    assert picture.meshes["ego_boxes"].color != picture.meshes["cav_boxes"].color
    assert "precision / recall" in picture.metrics_markdown and "CBM time" in picture.metrics_markdown


def test_ego_vehicle_sits_at_the_origin_facing_forward(explorer: Explorer) -> None:
    picture = drawing.draw(explorer.compute(Settings()), explorer.map_segments)
    vertices = picture.meshes["ego_vehicle"].vertices
    assert np.allclose(vertices[:, :2].mean(axis=0), [0.5, 0.0], atol=1.0)
    nose = vertices[vertices[:, 2] > 1.5]
    assert nose[:, 0].max() > 1.5, "the roof arrow points along +x"


def test_before_and_after_place_the_cav_by_init_and_by_the_estimate(explorer: Explorer) -> None:
    after = explorer.compute(_view(Settings(), layout="after"))
    before = explorer.compute(_view(Settings(), layout="before"))
    cav_after = drawing.draw(after, {}).objects["cav"][0]
    cav_before = drawing.draw(before, {}).objects["cav"][0]
    slim = np.array([1, 1, 1, cavs.SLIM[0], cavs.SLIM[0], 1, 1])
    assert np.allclose(cav_after, slim * se2.apply_boxes(after.result.transform, after.trial.cav_boxes))
    assert np.allclose(cav_before, slim * se2.apply_boxes(before.trial.init, before.trial.cav_boxes))
    assert "ego_before" in drawing.draw(before, {}).labels and "cav_after" in drawing.draw(after, {}).labels


def test_side_by_side_draws_two_copies_and_the_view_toggles_apply(explorer: Explorer) -> None:
    single = drawing.draw(explorer.compute(Settings()), {})
    both = drawing.draw(explorer.compute(_view(Settings(), layout="side by side", ghosts=True, lines=False)), {})
    assert len(both.meshes["ego_boxes"].faces) == 2 * len(single.meshes["ego_boxes"].faces)
    assert {"before", "after"} <= set(both.labels) and both.centre_y > 0
    assert len(both.lines["ghosts"].segments) > 0 and len(single.lines["ghosts"].segments) == 0
    assert len(both.lines["right"].segments) == 0


def test_wrong_thresholds_make_wrong_or_missed_lines(explorer: Explorer) -> None:
    tight = Settings().with_params("cbm", sigma2=0.25, sigma3=0.25, sigma1=1.0)
    settings = dataclasses.replace(tight, scenario=dataclasses.replace(tight.scenario, sigma_p=0.8, sigma_theta=10.0))
    picture = drawing.draw(explorer.compute(settings), {})
    assert len(picture.lines["missed"].segments) > 0


def test_recompute_is_reproducible_and_follows_the_settings(explorer: Explorer) -> None:
    a = explorer.compute(Settings())
    b = explorer.compute(Settings())
    c = explorer.compute(dataclasses.replace(Settings(), frame=40))
    assert np.array_equal(a.result.pairs, b.result.pairs) and np.allclose(a.trial.init, b.trial.init)
    assert c.frame_index == 40 and not np.allclose(a.trial.ego_pose, c.trial.ego_pose)


def test_an_edit_recomputes_on_the_kept_trial_and_gives_what_a_fresh_explorer_gives() -> None:
    kept = Explorer(loaders.open("synthetic:60"))
    base = Settings()
    edits = [base, base.with_params("cbm", sigma2=2.0), dataclasses.replace(base, method="icp"),
             base.with_scenario(sigma_p=0.6), base.with_params("cbm", sigma2=2.0), dataclasses.replace(base, frame=3)]
    outcomes = [kept.compute(settings) for settings in edits]
    assert outcomes[1].trial is outcomes[0].trial and outcomes[2].trial is outcomes[0].trial
    assert outcomes[3].trial is not outcomes[0].trial and outcomes[4].trial is outcomes[0].trial
    for settings, outcome in zip(edits, outcomes):
        fresh = Explorer(loaders.open("synthetic:60")).compute(settings)
        assert np.array_equal(outcome.result.pairs, fresh.result.pairs)
        assert np.array_equal(outcome.result.transform, fresh.result.transform)
        timeless = [dataclasses.replace(metrics, runtime_s=0.0)
                    for metrics in (outcome.metrics, fresh.metrics, outcome.limit, fresh.limit)]
        assert timeless[0] == timeless[1] and timeless[2] == timeless[3]


def test_every_method_runs(explorer: Explorer) -> None:
    for method in ("cbm", "cbm-no-consensus", "icp", "ricp", "vips"):
        outcome = explorer.compute(dataclasses.replace(Settings(), method=method))
        assert outcome.metrics.n_matched > 0, method


def test_cav_choice_and_fallback(explorer: Explorer) -> None:
    choices = explorer.cav_choices(0)
    assert choices and choices == sorted(choices, key=lambda c: c.distance)
    chosen = choices[-1].id
    assert explorer.compute(dataclasses.replace(Settings(), cav=chosen)).cav_id == chosen
    absent = explorer.compute(dataclasses.replace(Settings(), cav="no-such-vehicle"))
    assert absent.cav_id != "no-such-vehicle" and "not in this frame" in absent.cav_note


def test_clicking_a_box_names_it_and_its_match(explorer: Explorer) -> None:
    outcome = explorer.compute(Settings())
    picture = drawing.draw(outcome, {})
    boxes, _ = picture.objects["ego"]
    group, row = picking.pick(picture, boxes[0, :2])
    text = picking.describe(outcome, picture, group, row)
    assert text.startswith(group.upper()) and ("right" in text or "wrong" in text or "missed" in text
                                              or "one agent" in text)
    assert picking.pick(picture, np.array([1e4, 1e4])) is None


def test_synthetic_scene_without_map_or_agents() -> None:
    explorer = Explorer(loaders.open("synthetic"))
    sind = dataclasses.replace(Settings(), scenario=dataclasses.replace(Settings().scenario, protocol="sind"))
    picture = drawing.draw(explorer.compute(sind), explorer.map_segments)
    assert len(picture.meshes["ego_boxes"].faces) > 0


def test_concurrent_slider_callbacks_draw_only_the_last_state(explorer: Explorer) -> None:
    """Eight threads move sigma2 at once, as viser's thread pool does; the last drawing shown is
    the last state set, and far fewer recomputes ran than callbacks fired."""
    shown: list[tuple[float, int]] = []
    worker = Coalescer(lambda s: (s, drawing.draw(explorer.compute(s), explorer.map_segments)),
                       lambda result, generation: shown.append((result[0].cbm.sigma2, generation)),
                       lambda error: pytest.fail(str(error)))
    lock = threading.Lock()
    state = {"settings": Settings()}
    values = iter(np.round(np.linspace(0.5, 8.0, 160), 3).tolist())

    def slider() -> None:
        for _ in range(20):
            with lock:
                state["settings"] = state["settings"].with_params("cbm", sigma2=next(values))
                worker.submit(state["settings"])

    threads = [threading.Thread(target=slider) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert worker.wait_idle(timeout=30)
    worker.close()
    assert shown[-1] == (state["settings"].cbm.sigma2, 160)
    assert len(shown) < 40
    assert [g for _, g in shown] == sorted(g for _, g in shown)


def test_view_options_reject_unknown_layouts() -> None:
    with pytest.raises(ValueError, match="layout"):
        ViewOptions(layout="upside down")
    assert Settings().cav == AUTO_CAV


def test_opv2v_protocol_falls_back_to_sensor_range_without_visibility(explorer: Explorer) -> None:
    settings = dataclasses.replace(Settings(), scenario=dataclasses.replace(Settings().scenario, protocol="opv2v",
                                                                             localization="gaussian"))
    outcome = explorer.compute(settings)
    assert "sensor range" in outcome.cav_note and outcome.metrics.n_true > 0


def test_controls_reshown_unchanged_are_not_assigned_again_and_a_change_still_shows() -> None:
    """``reflect`` assigns only what differs from what a control holds (``panels.actions.assign``):
    a sigma2 edit assigns nothing; a method without CBM's parameters disables them, as before."""
    import viser

    from app.panels import method, scenario, view
    from app.panels.actions import assign
    from app.session.offers import offers_of

    class Held:
        disabled, hint = False, "a"

    held, written = Held(), []
    Held.__setattr__ = lambda self, name, value: (written.append(name), object.__setattr__(self, name, value))
    assign(held, disabled=False, hint="b")
    assert written == ["hint"] and held.hint == "b"
    sequence = loaders.open("synthetic:30")
    server = viser.ViserServer(port=0, verbose=False)
    try:
        parts = [panel.build(server.gui, Settings(), offers_of(sequence)) for panel in (scenario, method, view)]
        for part in parts:
            part.reflect(Settings())
        messages = []
        queue = server._websock_server.queue_message
        server._websock_server.queue_message = lambda message: (messages.append(message), queue(message))
        for part in parts:
            part.reflect(Settings().with_params("cbm", sigma2=2.5))
        assert messages == []
        for part in parts:
            part.reflect(dataclasses.replace(Settings(), method="icp"))
        assert messages
        sigma2 = parts[1].params[("cbm", "sigma2")]
        assert sigma2.disabled and sigma2.hint.startswith("Disabled: ")
    finally:
        server.stop()
