"""More than two agents: one trial per CAV and frame, the first CAV's trial today's two-agent trial
draw for draw, the others on streams of their own; ``evaluate.py --agents N``."""
import dataclasses

import numpy as np
import polars as pl
import pytest

import evaluation
import loaders
from evaluation.cli import main
from evaluation.scenario import ScenarioParams
from evaluation.trials import NoTrial, frame_cav_inputs, frame_inputs, sequence_inputs, short_frames

FIELDS = ("ego_boxes", "cav_boxes", "ego_ids", "cav_ids", "T_true", "init", "gt_pairs")
SCENARIO = ScenarioParams(protocol="range", sigma_p=0.3, sigma_theta=2.0)
SCENARIO_SIND = ScenarioParams(protocol="sind", eta=0.5)


@pytest.fixture(scope="module")
def sequence() -> loaders.Sequence:
    return loaders.open("argoverse2")


def _same(a, b) -> bool:
    return all(np.array_equal(getattr(a, name), getattr(b, name)) for name in FIELDS)


@pytest.mark.parametrize("protocol", ["range", "sind"])
def test_two_agents_give_todays_one_trial(sequence, protocol: str) -> None:
    frame = sequence[7]
    (only,) = frame_cav_inputs(frame, protocol, agents=2)
    scenario = dataclasses.replace(SCENARIO, protocol=protocol)
    assert only.stream == 0 and only.peers == ()
    assert _same(only.build(scenario, 3), frame_inputs(frame, protocol).build(scenario, 3))


def test_each_cav_has_its_own_trial_and_stream_and_sees_the_others_as_peers(sequence) -> None:
    frame = sequence[7]
    first, *others = frame_cav_inputs(frame, "range", agents=4)
    assert len(others) == 2
    cavs = [item.trial["cav_id"] for item in (first, *others)]
    assert cavs[0] == frame_inputs(frame, "range").trial["cav_id"] and len(set(cavs)) == 3
    assert [item.stream for item in (first, *others)] == [0, 1, 2]
    assert {peer.trial["cav_id"] for peer in first.peers} == set(cavs[1:])
    assert not _same(others[0].build(SCENARIO, 0), first.build(SCENARIO, 0))
    assert _same(others[0].build(SCENARIO, 0), others[0].build(SCENARIO, 0))
    peer_trials = first.peer_trials(SCENARIO, 0)
    assert _same(peer_trials[0], others[0].build(SCENARIO, 0))


@pytest.fixture
def few_path(tmp_path):
    """Frame 0: three vehicles and four pedestrians; frame 1: the pedestrians only."""
    rows = ["frame,track_id,category,x,y,length,width,yaw"]
    rows += [f"0,car{k},vehicle,{20 * k},{3 * k},4.5,1.9,0" for k in range(3)]
    rows += [f"{f},ped{k},pedestrian,{3 * k},{5 + k},0.5,0.5,0" for f in (0, 1) for k in range(4)]
    path = tmp_path / "few.csv"
    path.write_text("\n".join(rows) + "\n")
    return path


@pytest.fixture
def few_vehicles(few_path) -> loaders.Sequence:
    return loaders.open(few_path)


def test_a_frame_with_few_vehicles_gives_fewer_trials_and_is_counted_short(few_vehicles) -> None:
    inputs, skipped = sequence_inputs(few_vehicles, [0, 1], "range", agents=4)
    assert len(inputs) == 2 and skipped == [1]
    assert short_frames(inputs, agents=4) == [0] and short_frames(inputs, agents=3) == []


def test_the_summary_counts_the_frames_short_of_cavs(few_path, tmp_path, capsys) -> None:
    assert main(["--dataset", str(few_path), "--protocol", "range", "--agents", "4", "--methods", "cbm",
                 "--workers", "1", "--out", str(tmp_path / "out")]) == 0
    summary = (tmp_path / "out" / "summary.md").read_text()
    assert "1 frames (0); skipped 1 without an ego or a CAV: 1; 1 with fewer CAVs than asked" in summary


def test_sind_without_vehicles_deals_to_n_minus_1_abstract_cavs(few_vehicles) -> None:
    cavs = frame_cav_inputs(few_vehicles[1], "sind", agents=3)
    assert [item.stream for item in cavs] == [0, 1] and "abstract" in cavs[0].note
    first, second = (item.build(SCENARIO_SIND, 0) for item in cavs)
    assert not np.array_equal(first.ego_ids, second.ego_ids) or not np.array_equal(first.cav_ids, second.cav_ids)
    with pytest.raises(NoTrial):
        frame_cav_inputs(few_vehicles[1], "range", agents=3)


def test_fewer_than_two_agents_is_refused(sequence) -> None:
    with pytest.raises(ValueError, match="at least 2"):
        frame_cav_inputs(sequence[0], "range", agents=1)
    with pytest.raises(SystemExit) as stop:
        main(["--dataset", "synthetic:40", "--agents", "1", "--frames", "0"])
    assert stop.value.code == 2


def test_three_agents_give_twice_the_rows_of_two_each_named_by_its_cav() -> None:
    options = dict(methods=("cbm", "cbm-graph"), protocol="range", frames=lambda n: [0, 10, 20],
                   grid={"sigma_p": (0.3,)})
    two = evaluation.run(["argoverse2"], agents=2, **options)
    three = evaluation.run(["argoverse2"], agents=3, **options)
    assert len(three) == 2 * len(two)
    assert three.group_by("frame", "method").agg(pl.col("cav_id").n_unique())["cav_id"].to_list() == [2] * 6
    first = three.filter(pl.col("cav_id").is_in(two["cav_id"].unique().to_list()) & (pl.col("method") == "cbm"))
    assert first.drop("runtime_s").equals(two.filter(pl.col("method") == "cbm").drop("runtime_s"))
    graph = two.filter(pl.col("method") == "cbm-graph").drop("runtime_s", "method")
    assert graph.equals(two.filter(pl.col("method") == "cbm").drop("runtime_s", "method"))


def test_sequence_inputs_with_three_agents_list_every_cav_of_every_frame(sequence) -> None:
    inputs, skipped = sequence_inputs(sequence, [0, 1], "range", agents=3)
    assert not skipped and [item.index for item in inputs] == [0, 0, 1, 1]
