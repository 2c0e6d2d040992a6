"""SinD and INTERACTION track files."""
import numpy as np
import pytest

import loaders


def test_sind_handmade_recording(fixtures):
    seq = loaders.open(fixtures / "sind" / "handmade")
    assert seq.name == "sind/Handmade recording 9"
    assert seq.frame_ids == [0, 1, 2]
    np.testing.assert_allclose(seq.timestamps, [0.0, 0.1001001, 0.2002002])
    first = seq[0]
    assert list(first.track_ids) == ["1", "P1"]
    assert list(first.categories) == ["car", "pedestrian"]      # meta label "car " stripped
    car, walker = first.boxes()
    np.testing.assert_allclose(car, [10.0, 5.0, 0.8, 4.5, 1.8, 1.6, 0.1])   # yaw_rad, not heading_rad
    np.testing.assert_allclose(walker, [1.0, 2.0, 0.85, 0.6, 0.6, 1.7, np.pi / 4])
    bus = seq[1].boxes()[list(seq[1].track_ids).index("2")]
    np.testing.assert_allclose(bus, [-5.0, -3.0, 1.6, 12.0, 2.5, 3.2, 3.0])
    standing = seq[2].boxes()[list(seq[2].track_ids).index("P2")]
    assert standing[6] == 0.0                                       # 0.05 m/s: below walking speed


def test_sind_real_pedestrians(fixtures):
    seq = loaders.open(fixtures / "sind" / "Xian_412_m1" / "Ped_smoothed_tracks.csv")
    assert seq[0].frame_id == 76 and seq[0].track_ids[0] == "P0"
    np.testing.assert_allclose(seq[0].boxes()[0, :2], [-35.46949413587108, 32.35237500310035])
    np.testing.assert_allclose(seq[0].boxes()[0, 6], np.arctan2(-1.999125557248984, -4.102944146277136))
    np.testing.assert_allclose(seq.timestamps[0], 7.607607607608)


def test_sind_meta_only_folder_says_what_is_missing(fixtures):
    with pytest.raises(loaders.LoaderError, match="no SinD track file"):
        loaders.open(fixtures / "sind" / "Tianjin_8_2_1")


def test_sind_header_must_be_the_official_one(copy_fixture):
    folder = copy_fixture("sind/handmade")
    path = folder / "Veh_smoothed_tracks.csv"
    path.write_text(path.read_text().replace("yaw_rad,heading_rad", "heading_rad,yaw_rad", 1))
    with pytest.raises(loaders.LoaderError, match="header column 9 is 'heading_rad', expected 'yaw_rad'"):
        loaders.open(folder)


def test_sind_bad_value_names_row_and_column(copy_fixture):
    folder = copy_fixture("sind/handmade")
    path = folder / "Veh_smoothed_tracks.csv"
    lines = path.read_text().splitlines()
    lines[2] = lines[2].replace("11.0", "eleven", 1)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(loaders.LoaderError, match="row 2, column x: 'eleven' is not a number"):
        loaders.open(folder)


def test_sind_shared_real_files(shared_data):
    seq = loaders.open(shared_data / "sind" / "Xian_412_m1")
    assert len(seq) > 1000 and set(seq[0].categories) == {"pedestrian"}


def test_interaction_official_test_file(fixtures):
    seq = loaders.open(fixtures / "interaction" / "vehicle_tracks_000.csv")
    assert seq.frame_ids[0] == 1 and seq.timestamps[0] == 0.1
    np.testing.assert_allclose(seq[0].boxes()[0], [1.0, 2.5, 0.8, 4.0, 1.8, 1.6, 0.0])
    assert seq[0].categories[0] == "car"


def test_interaction_vehicles_and_pedestrians(fixtures):
    seq = loaders.open(fixtures / "interaction" / "handmade")
    assert seq.frame_ids == [1, 2]
    np.testing.assert_allclose(seq[0].boxes()[0], [1015.5, 980.2, 0.8, 4.6, 1.9, 1.6, 0.9273])
    walker = seq[1].boxes()[list(seq[1].track_ids).index("P1")]
    np.testing.assert_allclose(walker, [1000.0, 990.0, 0.85, 0.6, 0.6, 1.7, -np.pi / 2])


def test_interaction_folder_with_two_recordings(copy_fixture):
    folder = copy_fixture("interaction/handmade")
    (folder / "vehicle_tracks_002.csv").write_text((folder / "vehicle_tracks_001.csv").read_text())
    with pytest.raises(loaders.LoaderError, match="2 recordings"):
        loaders.open(folder)


def test_nan_coordinates_are_dropped_with_a_warning(copy_fixture):
    folder = copy_fixture("interaction/handmade")
    path = folder / "vehicle_tracks_001.csv"
    path.write_text(path.read_text().replace("1015.8", "nan"))
    with pytest.warns(UserWarning, match="dropped 1 row.*first: row 2"):
        seq = loaders.open(folder)
    assert seq.dropped_rows == 1 and list(seq[1].track_ids) == ["P1"]


def test_truncated_file_drops_the_cut_row(copy_fixture):
    folder = copy_fixture("sind/handmade")
    path = folder / "Veh_smoothed_tracks.csv"
    text = path.read_text()
    path.write_text(text[: text.rindex("\n", 0, len(text) - 1) + 25])
    with pytest.warns(UserWarning, match="dropped 1 row.*first: row 5"):
        seq = loaders.open(folder)
    assert seq.dropped_rows == 1
