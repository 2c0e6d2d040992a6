import numpy as np
import polars as pl
import pytest

import loaders


def test_generic_table_with_agents(fixtures):
    seq = loaders.open(fixtures / "table" / "boxes.csv")
    assert seq.frame_ids == [10, 11]
    np.testing.assert_allclose(seq.timestamps, [1.0, 1.1])
    first = seq[0]
    assert list(first.track_ids) == ["a", "b", "c"]
    np.testing.assert_allclose(first.boxes()[1], [10.0, 0.0, 0.8, 4.5, 1.8, 1.6, 3.1416])  # ground-truth row wins
    assert {k: sorted(v) for k, v in first.visibility.items()} == {"a": ["b", "c"], "b": ["a"]}
    np.testing.assert_allclose(first.agent_pose("b"), [[-1, 0, 10], [0, -1, 0], [0, 0, 1]], atol=1e-4)
    assert seq[1].agents["agent_id"].to_list() == ["a"]


def test_generic_table_minimal_columns_and_defaults(fixtures):
    with pytest.warns(UserWarning, match="dropped 1 row"):
        seq = loaders.open(fixtures / "table" / "minimal.csv")
    assert seq.frame_ids == [0, 2] and seq.agents is None and seq.visibility is None
    np.testing.assert_allclose(seq.timestamps, [0.0, 0.2])
    np.testing.assert_allclose(seq[0].boxes()[0], [0.0, 0.0, 0.75, 4.0, 2.0, 1.5, 0.5])
    assert seq[0].categories[0] == "unknown" and len(seq[1]) == 1


def test_generic_parquet_equals_csv(fixtures, tmp_path):
    table = pl.read_csv(fixtures / "table" / "boxes.csv", schema_overrides={"track_id": pl.Utf8, "agent": pl.Utf8})
    table.write_parquet(tmp_path / "boxes.parquet")
    a, b = loaders.open(fixtures / "table" / "boxes.csv"), loaders.open(tmp_path / "boxes.parquet")
    np.testing.assert_array_equal(a[0].boxes(), b[0].boxes())


def test_generic_table_errors(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text("frame,track_id,x,y,length,width\n0,1,0,0,4,2\n")
    with pytest.raises(loaders.LoaderError, match="missing column.*yaw"):
        loaders.open(path)
    path.write_text("frame,track_id,x,y,length,width,yaw\n0.5,1,0,0,4,2,0\n")
    with pytest.raises(loaders.LoaderError, match="row 1, column frame: '0.5' is not an integer"):
        loaders.open(path)
    path.write_text("frame,track_id,x,y,length,width,yaw\n")
    with pytest.raises(loaders.LoaderError, match="no data rows"):
        loaders.open(path)
    path.write_text("")
    with pytest.raises(loaders.LoaderError, match="empty"):
        loaders.open(path)


def test_open_picks_each_loader(fixtures):
    names = {
        fixtures / "argoverse2": "argoverse2/",
        fixtures / "sind" / "handmade": "sind/",
        fixtures / "interaction" / "vehicle_tracks_000.csv": "interaction/",
        fixtures / "opv2v" / "scenario": "opv2v/",
        fixtures / "v2v4real" / "scenario": "v2v4real/",
        fixtures / "dair_v2x" / "cooperative-vehicle-infrastructure" / "cooperative" / "data_info.json": "dair-v2x/",
        fixtures / "table" / "boxes.csv": "table/",
    }
    for path, prefix in names.items():
        assert loaders.open(path).name.startswith(prefix), path
        assert loaders.open(str(path)).name.startswith(prefix), path


def test_open_says_clearly_when_it_cannot(tmp_path):
    with pytest.raises(loaders.LoaderError, match="does not exist"):
        loaders.open(tmp_path / "nowhere")
    (tmp_path / "notes.txt").write_text("hello")
    with pytest.raises(loaders.LoaderError, match="nothing recognisable.*expected"):
        loaders.open(tmp_path)
    with pytest.raises(loaders.LoaderError, match="nothing recognisable"):
        loaders.open(tmp_path / "notes.txt")
    assert issubclass(loaders.LoaderError, ValueError)


def test_open_on_the_shared_data(shared_data):
    assert len(loaders.open(shared_data / "argoverse2")) == 156
    assert len(loaders.open(shared_data / "interaction")) == 100
    assert len(loaders.open(shared_data / "opv2v_schema" / "000069.yaml")[0]) == 1


def test_parquet_types(tmp_path):
    base = {"track_id": ["1", "2"], "x": [0.0, 1.0], "y": [0.0, 1.0], "length": [4.0, 4.0],
            "width": [2.0, 2.0], "yaw": [0.0, 0.0]}
    pl.DataFrame({**base, "frame": [0.0, 1.0], "category": ["car", "bus"]},
                 schema_overrides={"category": pl.Categorical}).write_parquet(tmp_path / "ok.parquet")
    assert list(loaders.open(tmp_path / "ok.parquet")[1].categories) == ["bus"]
    pl.DataFrame({**base, "frame": [0.0, 1.5]}).write_parquet(tmp_path / "bad.parquet")
    with pytest.raises(loaders.LoaderError, match="row 2, column frame: 1.5 is not an integer"):
        loaders.open(tmp_path / "bad.parquet")
    pl.DataFrame({**base, "frame": [0, 1], "x": [[0.0], [1.0]]}).write_parquet(tmp_path / "nested.parquet")
    with pytest.raises(loaders.LoaderError, match="column x has type List"):
        loaders.open(tmp_path / "nested.parquet")
