"""Issue 50, item 11: a method whose pairs cannot tell the pose abstains, with the reason, instead
of answering tens of metres off: boxes all at one point fix no rotation; with no prior, evenly
spaced boxes on a line look the same turned by a half turn."""
from __future__ import annotations

import math

import numpy as np
import pytest

from cbm import se2
from cbm.methods import run


def _boxes(xy: np.ndarray, yaw: float = 0.0) -> np.ndarray:
    boxes = np.zeros((len(xy), 7))
    boxes[:, :2], boxes[:, 3:6], boxes[:, 6] = xy, [4.5, 1.9, 1.6], yaw
    return boxes


def _seen_by_cav(ego: np.ndarray, T_true: np.ndarray) -> np.ndarray:
    return se2.apply_boxes(se2.inverse(T_true), ego)


def _error_m(result, T_true: np.ndarray) -> float:
    return float(np.hypot(*se2.translation_of(se2.inverse(T_true) @ result.transform)))


@pytest.mark.parametrize("spacing, yaw", [(8.0, 2.0), (10.0, -2.5), (5.0, -2.5)])
def test_cbm_without_a_prior_on_evenly_spaced_boxes_on_a_line_abstains(spacing: float, yaw: float) -> None:
    T_true = se2.make(30.0, -10.0, yaw)
    ego = _boxes(np.column_stack([np.arange(20) * spacing, np.zeros(20)]), 0.3)
    result = run("cbm-no-prior", ego, _seen_by_cav(ego, T_true), np.eye(3))
    assert result.abstained, f"answered {_error_m(result, T_true):.0f} m off without abstaining"
    assert result.reason == ("the paired objects' layout looks the same turned by 180° about its centre: a pose "
                             "turned so explains them as well")


@pytest.mark.parametrize("name", ["freealign", "vips", "oracle", "v2xregpp"])
def test_a_method_on_boxes_all_at_one_point_abstains(name: str) -> None:
    T_true = se2.make(30.0, -10.0, 0.5)
    ego = _boxes(np.tile([[10.0, 5.0]], (20, 1)))
    inputs = {"true_pairs": np.column_stack([np.arange(20), np.arange(20)])} if name == "oracle" else {}
    result = run(name, ego, _seen_by_cav(ego, T_true), se2.make(28.0, -9.0, 0.45), **inputs)
    assert result.estimated and result.abstained
    assert result.reason.endswith("paired objects lie at one point (within 1 m): their positions fix no rotation")


@pytest.mark.parametrize("name", ["cbm-no-prior", "freealign", "vips", "oracle", "cbm"])
def test_a_scene_that_tells_the_pose_is_answered_without_abstaining(name: str) -> None:
    rng = np.random.default_rng(3)
    T_true = se2.make(12.0, -4.0, 0.4)
    ego = _boxes(rng.uniform(-40.0, 40.0, (30, 2)), 0.0)
    ego[:, 6] = rng.uniform(-math.pi, math.pi, 30)
    inputs = {"true_pairs": np.column_stack([np.arange(30), np.arange(30)])} if name == "oracle" else {}
    result = run(name, ego, _seen_by_cav(ego, T_true), se2.make(13.0, -3.0, 0.45), **inputs)
    assert not result.abstained, result.reason
    assert _error_m(result, T_true) < 0.5
