"""Each agent's own capture time where a dataset keeps it (``Sequence.agent_times``), read from files in
the layout and encoding the producers publish: DAIR-V2X-C's and V2X-Seq-SPD's side ``data_info.json``
(``pointcloud_timestamp``, microseconds as strings). The OPV2V family keeps none (one file name, the
frame's counter, for every agent). A late message starts from the dataset's gap, never reaches into
another scenario, and is not made from DAIR-V2X-C's untracked samples."""
from __future__ import annotations

import contextlib
import json

import pytest

import loaders
from evaluation.scenario import ScenarioParams
from evaluation.trials import capture_gap, frame_inputs
from support import releases, releases_v2i

DAIR = "dair_v2x/cooperative-vehicle-infrastructure"


def test_dair_v2x_keeps_each_sides_sweep_time(fixtures) -> None:
    sequence = loaders.open(fixtures / DAIR)
    assert sequence.agent_times == {0: {"vehicle": 0.0, "infrastructure": pytest.approx(-0.040123)}}
    assert capture_gap(sequence[0], "vehicle", "infrastructure") == pytest.approx(0.040123)
    assert not sequence.tracked, "DAIR-V2X-C's track ids are label indices of sampled pairs"


def test_dair_v2x_release_times_every_pair_from_its_two_sweeps(tmp_path) -> None:
    sequence = loaders.open(releases.dair_release(tmp_path / "cooperative-vehicle-infrastructure"))
    for k, gap_us in enumerate(releases.DAIR_INFRA_US):
        times = sequence[k].agent_times()
        assert times["vehicle"] == pytest.approx(k / 10)
        assert times["infrastructure"] - times["vehicle"] == pytest.approx(gap_us / 1e6, abs=1e-9)


def test_dair_v2x_samples_make_no_late_message_and_say_so(tmp_path) -> None:
    sequence = loaders.open(releases.dair_release(tmp_path / "cooperative-vehicle-infrastructure"))
    delayed = ScenarioParams(protocol="range", sensor_range=200.0, delay_ms=200.0)
    inputs = frame_inputs(sequence[2], "range", window_s=delayed.window_s)
    assert inputs.gap_s == pytest.approx(0.098)
    assert "no late message is made" in inputs.note
    assert inputs.build(delayed, seed=0).message_age_s == 0.0, "pair 1's label indices are other objects"


def test_dair_v2x_without_side_files_keeps_no_times(copy_fixture) -> None:
    root = copy_fixture(DAIR)
    (root / "infrastructure-side" / "data_info.json").unlink()
    assert loaders.open(root).agent_times == {}


def test_a_dair_v2x_timestamp_that_is_no_number_is_refused_naming_file_and_entry(copy_fixture) -> None:
    root = copy_fixture(DAIR)
    info = root / "vehicle-side" / "data_info.json"
    entries = json.loads(info.read_text())
    entries[0]["pointcloud_timestamp"] = "16261551500x98000"
    info.write_text(json.dumps(entries))
    with pytest.raises(loaders.LoaderError, match=r"vehicle-side/data_info\.json.*\[0\]\.pointcloud_timestamp"):
        loaders.open(root)


def test_v2x_seq_spd_keeps_the_roadside_units_later_sweep(tmp_path) -> None:
    sequence = loaders.open(releases_v2i.spd_release(tmp_path / "V2X-Seq-SPD"))
    for frame in sequence:
        times = frame.agent_times()
        assert times["vehicle"] == pytest.approx(frame.timestamp)
        assert times["infrastructure"] - times["vehicle"] == pytest.approx(0.062874, abs=1e-9)
        assert capture_gap(frame, "vehicle", "infrastructure") == 0.0, "a later capture is no delay"


@pytest.mark.parametrize("write", [releases.opv2v_root, releases.v2xset_scenario, releases.v2x_real_root,
                                   releases.v2v4real_scenario])
def test_the_opv2v_family_keeps_no_agent_times(tmp_path, write) -> None:
    with pytest.warns(UserWarning) if write is releases.v2x_real_root else contextlib.nullcontext():
        sequence = loaders.open(write(tmp_path / "release"))
    assert sequence.agent_times == {} and sequence.tracked


def test_a_late_message_never_reaches_into_the_scenario_before(tmp_path) -> None:
    sequence = loaders.open(releases.opv2v_root(tmp_path / "OPV2V"))
    assert sequence.scenarios == {"train/2021_08_16_22_26_54": 0, "test/2021_08_18_19_48_05": 2}
    delayed = ScenarioParams(protocol="range", delay_ms=100.0)
    ages = [frame_inputs(sequence[k], "range", "650", window_s=delayed.window_s).build(delayed, seed=0).message_age_s
            for k in range(4)]
    assert ages == [0.0, pytest.approx(0.1), 0.0, pytest.approx(0.1)]

