"""Calibration and label files that lie are refused at load, naming the file, the field and what was
expected (issue 40, item 3): a rotation that is no rotation, a translation, offset, position or size
of 1e300 metres. Before, they were accepted (RTE 0.29 m instead of 0.09 m) or crashed far from the
file ("cost matrix is infeasible")."""
from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest

import loaders

FIXTURES = Path(__file__).resolve().parent / "fixtures"
DAIR = FIXTURES / "dair_v2x" / "cooperative-vehicle-infrastructure"
TO_WORLD = "infrastructure-side/calib/virtuallidar_to_world/000020.json"


def copied(tmp_path: Path, fixture: Path) -> Path:
    return shutil.copytree(fixture, tmp_path / fixture.name)


def rewrite_json(path: Path, change) -> None:
    record = json.loads(path.read_text())
    change(record)
    path.write_text(json.dumps(record))


@pytest.mark.parametrize("rotation", [[[2, 0, 0], [0, 2, 0], [0, 0, 2]], [[-1, 0, 0], [0, -1, 5.0], [0, 0, 1]],
                                      [[1, 0, 0], [0, 1, 0], [0, 0, -1]]])
def test_a_calibration_rotation_that_is_no_rotation_is_refused(tmp_path, rotation):
    root = copied(tmp_path, DAIR)
    rewrite_json(root / TO_WORLD, lambda calib: calib.update(rotation=rotation))
    with pytest.raises(loaders.LoaderError, match=re.escape(f"{TO_WORLD.split('/')[-1]}: rotation: expected a "
                                                            "rotation (orthonormal rows, determinant 1)")):
        loaders.open(root)


def test_a_calibration_translation_of_1e300_is_refused(tmp_path):
    root = copied(tmp_path, DAIR)
    rewrite_json(root / TO_WORLD, lambda calib: calib.update(translation=[[1e300], [0.0], [0.0]]))
    with pytest.raises(loaders.LoaderError, match=r"000020.json: translation\[0\]\[0\]: expected at most 1e\+06 "
                                                  r"metres in size, got 1e\+300"):
        loaders.open(root)


def test_a_system_error_offset_of_1e300_is_refused(tmp_path):
    root = copied(tmp_path, DAIR)
    rewrite_json(root / "cooperative" / "data_info.json",
                 lambda pairs: pairs[0].update(system_error_offset={"delta_x": 1e300, "delta_y": 0.0}))
    with pytest.raises(loaders.LoaderError, match=r"data_info.json: .*delta_x: expected at most 1e\+06 metres"):
        loaders.open(root)


def test_a_label_position_of_1e300_names_the_label_file_and_the_field(tmp_path):
    root = copied(tmp_path, DAIR)
    label = root / "vehicle-side" / "label" / "lidar" / "000010.json"
    rewrite_json(label, lambda boxes: boxes[0]["3d_location"].update(x=1e300))
    with pytest.raises(loaders.LoaderError, match=r"000010.json: \[0\].3d_location.x: expected at most 1e\+06 "
                                                  r"metres in size, got 1e\+300"):
        loaders.open(root)


@pytest.mark.parametrize("fixture, file, old, new, column", [
    ("interaction/handmade", "vehicle_tracks_001.csv", "1015.5", "1e300", "x"),
    ("sind/handmade", "Veh_smoothed_tracks.csv", ",4.5,1.8,", ",4.5,1e300,", "width"),
    ("opv2v/scenario", "641/000068.yaml", "extent: [2.25, 1, 0.75]", "extent: [0.5e+300, 1, 0.75]", "length"),
])
def test_a_size_or_position_of_1e300_is_refused_in_every_format(tmp_path, fixture, file, old, new, column):
    root = copied(tmp_path, FIXTURES / fixture)
    path = root / file
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(loaders.LoaderError, match=rf": {column} = 1e\+300; expected positions and sizes within"):
        loaders.open(root)
