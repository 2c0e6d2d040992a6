"""Issue 50, items 4 and 5: an agent's file that cannot be read is an error naming it, never an
agent left out without a word; V2X-Real's published example folder ``infra_2`` loads as the
roadside unit its file says it is. Releases in their published layout (``support.releases``)."""
from __future__ import annotations

import os
from pathlib import Path

import pytest

import loaders
from support import releases

WRITERS = {
    "opv2v": (lambda root: releases.opv2v_root(root / "OPV2V") / "train" / "2021_08_16_22_26_54", "641"),
    "v2v4real": (lambda root: releases.v2v4real_scenario(root / "testoutput_CAV_data_2022-03-15-09-54-40_0"), "1"),
    "v2x_real": (lambda root: releases.v2x_real_root(root / "v2xreal") / "train" / "2023-03-17-15-53-02_1_0", "2"),
}


def _unreadable(path: Path, how: str) -> str:
    """Replace the file ``path`` by a folder or a symlink loop; what the error is to say."""
    path.unlink()
    if how == "folder":
        path.mkdir()
        return "a folder, not a file"
    os.symlink(path.name, path)
    return "cannot read it (Too many levels of symbolic links)"


@pytest.mark.parametrize("how", ["folder", "symlink loop"])
@pytest.mark.parametrize("release", sorted(WRITERS))
def test_an_agent_file_that_cannot_be_read_is_an_error_naming_it(tmp_path: Path, release: str, how: str) -> None:
    write, agent = WRITERS[release]
    scenario = write(tmp_path)
    loaders.open(scenario)
    path = sorted((scenario / agent).glob("*.yaml"))[0]
    words = _unreadable(path, how)
    with pytest.raises(loaders.LoaderError) as raised:
        loaders.open(scenario)
    assert str(raised.value) == f"{path}: {words}"


@pytest.mark.parametrize("opened", ["file", "folder"])
def test_v2x_reals_example_infra_2_is_the_roadside_unit_its_flag_says(tmp_path: Path, opened: str) -> None:
    """The dataset tool's ``data_examples/v2x-real/infra_2/000000.yaml`` (``infra: true``)."""
    path = tmp_path / "data_examples" / "v2x-real" / "infra_2" / "000000.yaml"
    releases.dump_yaml(path, releases.v2x_real_record("-1", 0))
    with pytest.warns(UserWarning, match=r"infra_2: not an agent id; read as agent -2 \(infrastructure, as its "
                                         r"files' infra flag says\)"):
        sequence = loaders.open(path if opened == "file" else path.parent)
    assert sequence.ego == "-2" and list(sequence[0].agents["agent_id"]) == ["-2"]
    assert any(note.startswith("infra_2: not an agent id") for note in sequence.notes)
    assert len(sequence[0].track_ids) > 0


def test_a_vehicle_folder_not_named_by_an_id_takes_its_digits(tmp_path: Path) -> None:
    path = tmp_path / "vehicle_1" / "000000.yaml"
    releases.dump_yaml(path, releases.v2x_real_record("1", 0))
    with pytest.warns(UserWarning, match=r"vehicle_1: not an agent id; read as agent 1 \(a vehicle"):
        assert loaders.open(path).ego == "1"
