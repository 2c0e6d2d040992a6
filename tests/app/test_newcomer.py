"""The words, offers and defaults behind what a newcomer reads (issue 24, items 7, 8, 12), without a browser."""
from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import loaders
from app.scene.text import metrics_markdown
from app.scene.words import TRACKING, WORDS
from app.session.explorer import Explorer
from app.session.names import agent_name
from app.session.offers import offers_of
from app.session.presets import discover
from app.session.settings import Settings, ViewOptions
from cbm import TrackingParams
from cbm.methods import METHODS


def test_every_parameter_has_a_label_in_words_and_a_hint() -> None:
    for method in METHODS.values():
        for name in method.params.__dataclass_fields__:
            label, hint = WORDS[(method.params_key, name)]
            assert "_" not in label and len(hint.split()) >= 4, (method.name, name)


def test_every_tracking_parameter_has_a_label_with_its_unit_and_its_docstring_as_hint() -> None:
    for field in dataclasses.fields(TrackingParams):
        label, hint = WORDS[(TRACKING, field.name)]
        assert re.fullmatch(r"[^_()]+ \([^()]+\)", label) and len(hint.split()) >= 4, field.name
    assert WORDS[(TRACKING, "gate")][1].startswith("Mahalanobis distance (standard deviations, 3 degrees of freedom)")
    assert "MatchResult.evidence_margin" in WORDS[(TRACKING, "sure_margin")][1], "code marks are dropped"


def test_the_recording_car_is_named_once() -> None:
    assert agent_name("ego", "ego") == "ego" and agent_name("CAV", "0af5cc06-3634", code=True) == "CAV `0af5cc06`"


def test_the_header_of_the_shipped_scene_names_the_ego_once(explorer: Explorer) -> None:
    header = metrics_markdown(explorer.compute(Settings())).splitlines()[0]
    assert header.startswith("**Frame 0** · ego · CAV `0af5cc06`"), header


def test_the_default_preset_is_the_apps_defaults_view_included(tmp_path) -> None:
    presets, _ = discover(users=tmp_path)
    assert presets["default"].apply(Settings()) == Settings()
    teaching = presets["teaching"].apply(Settings())
    back = presets["default"].apply(dataclasses.replace(teaching, view=dataclasses.replace(
        teaching.view, presentation=True, dark=True)))
    assert back.view == ViewOptions(presentation=True, dark=True), "default resets the view but the tab's theme"


def test_what_the_shipped_scene_cannot_offer_and_why(explorer: Explorer) -> None:
    offers = offers_of(explorer.sequence)
    assert "no LiDAR points" in offers.points and "no noisy CAV poses" in offers.reported_poses
    own_pose = Settings().with_scenario(localization="dataset")
    assert "localization 'dataset' is not offered" in offers.refusal(own_pose)
    graph = dataclasses.replace(Settings(), method="cbm-graph")
    assert "not offered with 1 CAV" in offers.refusal(graph)
    assert offers.refusal(dataclasses.replace(graph, cavs=2)) is None and offers.refusal(Settings()) is None


def test_fewer_cavs_than_the_pose_graph_needs_switch_the_method_to_cbm_and_say_so(explorer: Explorer) -> None:
    offers = offers_of(explorer.sequence)
    three = dataclasses.replace(Settings(), method="cbm-graph", cavs=3)
    switched, words = offers.adapted(three, dataclasses.replace(three, cavs=1))
    assert (switched.method, switched.cavs, switched.cbm) == ("cbm", 1, three.cbm) and offers.refusal(switched) is None
    assert words.startswith(f"{METHODS['cbm-graph'].label} needs 2 CAVs or more, so with 1 CAV the method is now CBM")
    assert offers.adapted(three, dataclasses.replace(three, cavs=2)) == (dataclasses.replace(three, cavs=2), None)
    chosen = dataclasses.replace(Settings(), method="cbm-graph")
    assert offers.adapted(Settings(), chosen) == (chosen, None), "choosing the graph at 1 CAV is refused, not switched"


def test_an_opv2v_release_offers_its_points_and_poses() -> None:
    fixtures = Path(__file__).resolve().parents[1] / "loaders" / "fixtures"
    assert offers_of(loaders.open(str(fixtures / "opv2v" / "scenario"))).reported_poses is None
    assert offers_of(loaders.open(str(fixtures / "opv2v_points" / "scenario"))).points is None
