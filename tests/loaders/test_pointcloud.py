"""LiDAR points from OPV2V .pcd files (ASCII and binary), through Frame.points."""
import numpy as np
import pytest

import loaders
from loaders.pointcloud import read_pcd

SCENARIO = "opv2v_points/scenario"


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


def test_truncated_binary_and_bad_header_are_named(tmp_path, fixtures):
    source = (fixtures / SCENARIO / "650" / "000068.pcd").read_bytes()
    truncated = tmp_path / "short.pcd"
    truncated.write_bytes(source[:-20])
    with pytest.raises(loaders.LoaderError, match=r"short.pcd: DATA binary: expected 40 points of 16 bytes"):
        read_pcd(truncated)
    headless = tmp_path / "headless.pcd"
    headless.write_bytes(b"VERSION 0.7\nFIELDS x y z\nDATA ascii\n1 2 3\n")
    with pytest.raises(loaders.LoaderError, match=r"headless.pcd: PCD header: missing SIZE, TYPE, COUNT, POINTS"):
        read_pcd(headless)
    compressed = tmp_path / "lzf.pcd"
    compressed.write_bytes(source.replace(b"DATA binary", b"DATA binary_compressed"))
    with pytest.raises(loaders.LoaderError, match="DATA: expected ascii or binary, got 'binary_compressed'"):
        read_pcd(compressed)
