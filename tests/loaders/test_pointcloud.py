"""LiDAR points from .pcd files in every encoding, written by pypcd4 (as PCL writes them), through
``read_pcd`` and ``Frame.points``."""
import numpy as np
import pypcd4
import pytest

import loaders
from loaders.pointcloud import read_pcd

SCENARIO = "opv2v_points/scenario"
ENCODINGS = ("ascii", "binary", "binary_compressed")


def dair_like_sweep(n: int = 2000) -> np.ndarray:
    """``(n, 4)`` x y z intensity on rings around the sensor, as a DAIR-V2X sweep holds them."""
    k = np.arange(n)
    ring = 5.0 + (k % 16)
    angle = k * 0.37
    return np.column_stack([ring * np.cos(angle), ring * np.sin(angle), -1.7 + 0.01 * (k % 16),
                            (k % 255).astype(float)]).astype(np.float32)


def written(tmp_path, points: np.ndarray, encoding: str, name: str = "sweep.pcd"):
    path = tmp_path / name
    pypcd4.PointCloud.from_xyzi_points(points).save(path, encoding=pypcd4.Encoding(encoding))
    return path


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_each_encoding_of_a_dair_style_header_reads_x_y_z(tmp_path, encoding):
    sweep = dair_like_sweep()
    path = written(tmp_path, sweep, encoding)
    assert f"DATA {encoding}\n".encode() in path.read_bytes()[:300]
    assert b"FIELDS x y z intensity\n" in path.read_bytes()[:300]
    points = read_pcd(path)
    assert points.shape == (len(sweep), 3) and points.dtype == np.float32
    np.testing.assert_allclose(points, sweep[:, :3], atol=1e-6)


def test_compressed_sweeps_are_smaller_and_equal(tmp_path):
    sweep = dair_like_sweep(20000)
    binary, compressed = (written(tmp_path, sweep, e, f"{e}.pcd") for e in ("binary", "binary_compressed"))
    assert compressed.stat().st_size < binary.stat().st_size
    np.testing.assert_array_equal(read_pcd(compressed), read_pcd(binary))


def test_open3d_ascii_fields_and_padding_fields(tmp_path):
    """Open3D's OPV2V sweeps: ``x y z rgb`` (rgb packed in a float); PCL's ``_`` padding fields."""
    path = tmp_path / "o3d.pcd"
    path.write_bytes(b"# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\n"
                     b"TYPE F F F F\nCOUNT 1 1 1 1\nWIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n"
                     b"1.5 -2 0.25 1.127595375e-38\n3 4 5 0\n")
    np.testing.assert_allclose(read_pcd(path), [[1.5, -2, 0.25], [3, 4, 5]])
    padded = np.zeros(3, dtype=[("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("_", "<f4"), ("intensity", "<f4")])
    padded["x"] = [1, 2, 3]
    metadata = pypcd4.MetaData.model_validate({"fields": ("x", "y", "z", "_", "intensity"), "size": (4,) * 5,
                                               "type": ("F",) * 5, "count": (1,) * 5, "points": 3, "width": 3})
    pypcd4.PointCloud(metadata, padded).save(tmp_path / "pad.pcd", encoding=pypcd4.Encoding.BINARY)
    np.testing.assert_allclose(read_pcd(tmp_path / "pad.pcd")[:, 0], [1, 2, 3])


def test_ascii_and_binary_sweeps_in_right_handed_agent_frames(fixtures):
    frame = loaders.open(fixtures / SCENARIO)[0]
    ego = frame.points("641")                       # DATA ascii: a ring of 40 points, 6 m around the sensor
    assert ego.shape == (40, 3) and ego.dtype == np.float32
    np.testing.assert_allclose(ego[10], [0.0, -6.0, -1.0], atol=1e-4)  # (0, 6, -1) in CARLA's left-handed frame
    cav = frame.points("650")                       # DATA binary: x = 2 + 0.5 k on the sensor's axis
    np.testing.assert_allclose(cav[:3], [[2.0, 0.0, -1.0], [2.5, 0.0, -1.0], [3.0, 0.0, -1.0]])
    assert frame.points("-1") is None               # no such agent / no .pcd: None


def test_datasets_without_points_give_none(fixtures):
    assert loaders.open(fixtures / "opv2v" / "scenario")[0].points("641") is None


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_truncated_files_are_named_in_one_line(tmp_path, encoding):
    source = written(tmp_path, dair_like_sweep(), encoding).read_bytes()
    truncated = tmp_path / "short.pcd"
    truncated.write_bytes(source[: len(source) - 100])
    with pytest.raises(loaders.LoaderError, match=rf"short.pcd: DATA {encoding}: expected 2000 points") as error:
        read_pcd(truncated)
    assert "\n" not in str(error.value)


def test_bad_header_no_xyz_and_lfs_pointer_are_named(tmp_path):
    headless = tmp_path / "headless.pcd"
    headless.write_bytes(b"VERSION 0.7\nFIELDS x y z\nDATA ascii\n1 2 3\n")
    with pytest.raises(loaders.LoaderError, match=r"headless.pcd: PCD header: missing SIZE, TYPE, COUNT, POINTS"):
        read_pcd(headless)
    flat = tmp_path / "flat.pcd"
    pypcd4.PointCloud.from_points([np.ones(3, np.float32)] * 2, ("a", "b"), (np.float32, np.float32)).save(flat)
    with pytest.raises(loaders.LoaderError, match=r"flat.pcd: PCD header FIELDS: expected x, y and z, got 'a b'"):
        read_pcd(flat)
    pointer = tmp_path / "000010.pcd"
    pointer.write_bytes(b"version https://git-lfs.github.com/spec/v1\noid sha256:" + b"0" * 64 + b"\nsize 1843\n")
    with pytest.raises(loaders.LoaderError, match=r"000010.pcd is a Git LFS pointer, not the data: run `git lfs pull`"):
        read_pcd(pointer)
