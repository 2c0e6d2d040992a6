"""Mangled fixtures and random bytes: every loader answers with a LoaderError or a sequence,
never another exception."""
import shutil
import tempfile
import warnings
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import loaders

FIXTURES = Path(__file__).resolve().parent / "fixtures"
AV2 = "argoverse2/adcf7d18-0510-35b0-a2fa-b4cea13a6d76"
DAIR = "dair_v2x/cooperative-vehicle-infrastructure"
CASES = {
    "argoverse2": (AV2, "", ["annotations.feather", "city_SE3_egovehicle.feather",
                             "map/log_map_archive_adcf7d18-0510-35b0-a2fa-b4cea13a6d76____PIT_city_57819.json"]),
    "sind": ("sind/handmade", "", ["Veh_smoothed_tracks.csv", "Ped_smoothed_tracks.csv",
                                   "Veh_tracks_meta.csv", "recording_metas.csv"]),
    "interaction": ("interaction/handmade", "", ["vehicle_tracks_001.csv", "pedestrian_tracks_001.csv"]),
    "opv2v": ("opv2v/scenario", "", ["641/000068.yaml", "650/000068.yaml", "-1/000070.yaml"]),
    "v2v4real": ("v2v4real/scenario", "", ["0/000000.yaml", "1/000000.yaml"]),
    "dair_v2x": (DAIR, "", ["cooperative/data_info.json", "vehicle-side/label/lidar/000010.json",
                            "infrastructure-side/label/virtuallidar/000020.json",
                            "vehicle-side/calib/lidar_to_novatel/000010.json",
                            "infrastructure-side/calib/virtuallidar_to_world/000020.json",
                            "vehicle-side/data_info.json", "infrastructure-side/data_info.json"]),
    "table": ("table", "boxes.csv", ["boxes.csv"]),
}
TOKENS = ["", ",", "\n", "nan", "inf", "-inf", "1e309", "abc", '"', "-", "{", "]", ":", "null", "\x00",
          "999999999999999999999"]


def mangle(data: bytes, draw) -> bytes:
    kind = draw(st.sampled_from(["random", "truncate", "flip", "insert", "drop_line"]))
    if kind == "random" or not data:
        return draw(st.binary(max_size=400))
    at = draw(st.integers(0, len(data)))
    if kind == "truncate":
        return data[:at]
    if kind == "flip":
        out = bytearray(data)
        for position in draw(st.lists(st.integers(0, len(data) - 1), min_size=1, max_size=8)):
            out[position] = draw(st.integers(0, 255))
        return bytes(out)
    if kind == "insert":
        return data[:at] + draw(st.sampled_from(TOKENS)).encode() + data[at:]
    lines = data.split(b"\n")
    del lines[draw(st.integers(0, len(lines) - 1))]
    return b"\n".join(lines)


def load_everything(path: Path) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        seq = loaders.open(path)
        for frame in seq:
            frame.boxes(), frame.objects, frame.agents, frame.visibility, frame.track_ids


@pytest.mark.parametrize("case", sorted(CASES))
@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_mangled_fixture_gives_only_loader_errors(case, data):
    folder, entry, files = CASES[case]
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp) / Path(folder).name
        shutil.copytree(FIXTURES / folder, root)
        target = root / data.draw(st.sampled_from(files))
        target.write_bytes(mangle(target.read_bytes(), data.draw))
        try:
            load_everything(root / entry)
        except loaders.LoaderError:
            pass


@settings(max_examples=40, deadline=None)
@given(content=st.binary(max_size=600),
       name=st.sampled_from(["annotations.feather", "Veh_smoothed_tracks.csv", "Ped_smoothed_tracks.csv",
                             "vehicle_tracks_000.csv", "t.csv", "t.parquet", "t.yaml", "t.feather"]))
def test_random_bytes_give_only_loader_errors(content, name):
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / name
        path.write_bytes(content)
        try:
            load_everything(path)
        except loaders.LoaderError:
            pass


@settings(max_examples=15, deadline=None)
@given(content=st.binary(max_size=300))
def test_random_bytes_in_a_dair_index(content):
    with tempfile.TemporaryDirectory() as tmp:
        index = Path(tmp) / "cooperative" / "data_info.json"
        index.parent.mkdir()
        index.write_bytes(content)
        with pytest.raises(loaders.LoaderError):
            load_everything(Path(tmp))


@pytest.mark.parametrize("case, path", [("argoverse2", CASES["argoverse2"][2][2]),
                                        ("dair_v2x", "cooperative/data_info.json"), ("opv2v", "641/000068.yaml")])
def test_deeply_nested_json_or_yaml_is_a_loader_error_naming_the_file(case, path, tmp_path):
    folder, entry, _ = CASES[case]
    root = tmp_path / Path(folder).name
    shutil.copytree(FIXTURES / folder, root)
    (root / path).write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(loaders.LoaderError, match=f"{Path(path).name}: not valid"):
        load_everything(root / entry)
