"""The prior-free methods held to their defining behaviour on constructed scenes: V2X-Reg++ registers
from single box correspondences, FreeAlign grows its common subgraph only along consistent edges,
and CBM without a prior finds the pose whatever the rotation between the agents."""
from __future__ import annotations

import numpy as np
import pytest

from cbm import se2
from cbm.baselines import FreeAlignParams, V2XRegParams
from cbm.baselines.freealign import common_subgraph
from cbm.baselines.v2xregpp import kept_boxes, kind_of, kinds_of
from cbm.methods import run

TRUE = se2.make(31.0, -12.0, 2.3)
"""A CAV 33 m away, turned by 132 degrees: no prior near it."""


def car(x: float, y: float, yaw: float, length: float = 4.5, width: float = 1.9) -> list[float]:
    return [x, y, 0.0, length, width, 1.6, yaw]


def seen_by_cav(ego: np.ndarray) -> np.ndarray:
    return se2.apply_boxes(se2.inverse(TRUE), ego)


def pose_error(T: np.ndarray) -> tuple[float, float]:
    """(metres, degrees) between ``T`` and the true pose."""
    error = se2.inverse(TRUE) @ T
    return float(np.hypot(*error[:2, 2])), float(np.degrees(abs(se2.yaw_of(error))))


def test_v2xregpp_finds_the_pose_from_two_boxes_without_a_prior() -> None:
    ego = np.array([car(5.0, 2.0, 0.4), car(-8.0, 11.0, 1.9, length=12.0, width=2.5)])
    result = run("v2xregpp", ego, seen_by_cav(ego)[::-1], np.eye(3), labels=(np.array(["car", "bus"]),
                                                                              np.array(["bus", "car"])))
    assert result.estimated and {tuple(p) for p in result.pairs} == {(0, 1), (1, 0)}
    metres, degrees = pose_error(result.transform)
    assert metres < 1e-9 and degrees < 1e-9


def test_v2xregpp_oiou_affinity_counts_overlaps_and_finds_the_same_pose() -> None:
    ego = np.array([car(5.0, 2.0, 0.4), car(-8.0, 11.0, 1.9), car(14.0, -6.0, -1.0)])
    result = run("v2xregpp", ego, seen_by_cav(ego), np.eye(3), V2XRegParams(affinity="oiou"))
    assert len(result.pairs) == 3 and pose_error(result.transform)[0] < 1e-9


def test_v2xregpp_pairs_only_boxes_of_one_kind() -> None:
    ego = np.array([car(5.0, 2.0, 0.4), car(-8.0, 11.0, 1.9)])
    result = run("v2xregpp", ego, seen_by_cav(ego), np.eye(3),
                 labels=(np.array(["car", "car"]), np.array(["pedestrian", "pedestrian"])))
    assert len(result.pairs) == 0 and not result.estimated
    np.testing.assert_array_equal(result.transform, np.eye(3))


def test_v2xregpp_keeps_buses_then_trucks_then_the_largest_cars() -> None:
    boxes = np.array([car(0, 0, 0), car(1, 0, 0, length=5.5), car(2, 0, 0, length=9.0), car(3, 0, 0, length=12.0),
                      car(150, 0, 0, length=12.0)])
    kinds = kinds_of(np.array(["Car", "REGULAR_VEHICLE", "truck", "BUS", "bus"]), 5)
    assert list(kinds) == ["car", "car", "truck", "bus", "bus"]
    assert list(kept_boxes(boxes, kinds, V2XRegParams(top_k=3))) == [3, 2, 1]
    assert kind_of("ScooterRider") == "small" and kind_of("TrashCan") == "detected"


def consistent_scene() -> tuple[np.ndarray, np.ndarray]:
    """Eight objects both agents see, plus one decoy each: the ego's decoy lies as far from object 0
    as the CAV's does, but elsewhere, so its edges to the other objects disagree."""
    rng = np.random.default_rng(4)
    ego = np.array([car(x, y, rng.uniform(-3, 3)) for x, y in rng.uniform(-25, 25, (8, 2))])
    cav = seen_by_cav(ego)
    reach = 9.0
    ego_decoy = np.array([car(ego[0, 0] + reach, ego[0, 1], 0.0)])
    cav_decoy = np.array([car(cav[0, 0], cav[0, 1] - reach, 0.0)])
    return np.vstack([ego, ego_decoy]), np.vstack([cav, cav_decoy])


def test_freealign_grows_only_along_consistent_edges() -> None:
    ego, cav = consistent_scene()
    edges_to_seed = abs(np.hypot(*(ego[8, :2] - ego[0, :2])) - np.hypot(*(cav[8, :2] - cav[0, :2])))
    assert edges_to_seed < 1e-9
    pairs = {tuple(p) for p in common_subgraph(ego[:, :2], cav[:, :2], FreeAlignParams())}
    assert pairs == {(k, k) for k in range(8)}
    result = run("freealign", ego, cav, np.eye(3))
    assert pose_error(result.transform)[0] < 1e-9


def test_freealign_needs_more_pairs_than_its_fewest_anchors() -> None:
    ego, cav = consistent_scene()
    assert len(common_subgraph(ego[:3, :2], cav[:3, :2], FreeAlignParams())) == 0
    assert len(common_subgraph(ego[:4, :2], cav[:4, :2], FreeAlignParams())) == 4
    assert len(common_subgraph(ego[:4, :2], cav[:4, :2], FreeAlignParams(min_anchors=4))) == 0


def scattered_scene(yaw: float, seed: int = 2) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(ego, CAV, true pose): 30 cars seen by both, the CAV's pose turned by ``yaw``, half the
    detected headings turned by pi, 0.2 m of position noise."""
    rng = np.random.default_rng(seed)
    true = se2.make(40.0, -15.0, yaw)
    ego = np.array([car(x, y, h) for (x, y), h in zip(rng.uniform(-40, 40, (30, 2)), rng.uniform(-np.pi, np.pi, 30))])
    cav = se2.apply_boxes(se2.inverse(true), ego)
    for boxes in (ego, cav):
        boxes[:, :2] += rng.normal(0.0, 0.2, (30, 2))
        boxes[:, 6] += np.pi * (rng.random(30) < 0.5)
    return ego, cav, true


@pytest.mark.parametrize("yaw_deg", [0, 60, 100, 135, 180, 230, 275, 330])
def test_cbm_without_a_prior_finds_the_pose_at_any_rotation(yaw_deg: int) -> None:
    ego, cav, true = scattered_scene(np.radians(yaw_deg))
    result = run("cbm-no-prior", ego, cav, np.eye(3))
    error = se2.inverse(true) @ result.transform
    assert np.hypot(*error[:2, 2]) < 0.3 and abs(se2.yaw_of(error)) < np.radians(1.0)
    assert len(result.pairs) >= 25
    np.testing.assert_array_equal(result.init, np.eye(3))


def test_cbm_with_the_identity_for_a_prior_fails_where_the_prior_free_mode_does_not() -> None:
    ego, cav, true = scattered_scene(np.radians(135))
    error = se2.inverse(true) @ run("cbm", ego, cav, np.eye(3)).transform
    assert np.hypot(*error[:2, 2]) > 5.0
