"""The pose graph of more than two agents (``cbm.posegraph``): exact on consistent edges, pulled
to agreement by the CAV-CAV edges, CBM itself without peers, and as the ``cbm-graph`` method."""
import numpy as np

from cbm import se2
from cbm.methods import METHODS
from cbm.pipeline import match
from cbm.posegraph import Edge, solve
from evaluation.scenario import ScenarioParams, make_trial

TRUTH = [se2.make(20.0, 5.0, 0.3), se2.make(-15.0, 10.0, -1.0), se2.make(5.0, -25.0, 2.0)]


def _pose_error(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(se2.translation_of(a) - se2.translation_of(b)))


def _edges(noisy_ego_edge: np.ndarray | None = None) -> list[Edge]:
    """Every ego-CAV and CAV-CAV edge of ``TRUTH``, the first ego edge replaced when given."""
    edges = [Edge(0, i + 1, T, 10.0) for i, T in enumerate(TRUTH)]
    if noisy_ego_edge is not None:
        edges[0] = Edge(0, 1, noisy_ego_edge, 10.0)
    pairs = [(0, 1), (0, 2), (1, 2)]
    return edges + [Edge(i + 1, j + 1, se2.inverse(TRUTH[i]) @ TRUTH[j], 10.0) for i, j in pairs]


def test_consistent_edges_give_the_true_poses_from_a_wrong_start() -> None:
    start = [se2.make(*(se2.translation_of(T) + 2.0), se2.yaw_of(T) + 0.08) for T in TRUTH]
    for solved, truth in zip(solve(start, _edges()), TRUTH):
        np.testing.assert_allclose(solved, truth, atol=1e-6)


def test_the_cav_to_cav_edges_pull_a_wrong_ego_edge_back() -> None:
    wrong = se2.make(21.0, 5.0, 0.3)
    solved = solve(TRUTH, _edges(noisy_ego_edge=wrong))
    assert _pose_error(solved[0], TRUTH[0]) < 0.6 * _pose_error(wrong, TRUTH[0])


def test_a_cav_no_edge_links_to_the_ego_keeps_its_start() -> None:
    start = [T @ se2.make(1.0, 0.0, 0.0) for T in TRUTH]
    solved = solve(start, [Edge(0, 1, TRUTH[0], 5.0)])
    np.testing.assert_allclose(solved[0], TRUTH[0], atol=1e-6)
    np.testing.assert_array_equal(solved[1], start[1])
    np.testing.assert_array_equal(solved[2], start[2])


def _trials(n: int) -> list:
    rng = np.random.default_rng(0)
    boxes = np.zeros((40, 7))
    boxes[:, :2] = rng.uniform(-30, 30, (40, 2))
    boxes[:, 3:6] = (4.5, 1.9, 1.6)
    boxes[:, 6] = rng.uniform(-np.pi, np.pi, 40)
    params = ScenarioParams(protocol="range", sigma_p=0.3, sigma_theta=2.0, sensor_range=60.0)
    ego = se2.make(0.0, 0.0, 0.0)
    return [make_trial(boxes, np.arange(40), params, ego_pose=ego, cav_pose=se2.make(8.0 * k, -5.0 * k, 0.2 * k),
                       rng=np.random.default_rng(k)) for k in range(1, n + 1)]


def test_cbm_graph_without_peers_is_cbm_and_with_peers_stays_accurate() -> None:
    trial, *peers = _trials(3)
    graph = METHODS["cbm-graph"]
    alone = graph(trial.ego_boxes, trial.cav_boxes, trial.init)
    plain = match(trial.ego_boxes, trial.cav_boxes, trial.init)
    np.testing.assert_array_equal(alone.transform, plain.transform)
    joint = graph(trial.ego_boxes, trial.cav_boxes, trial.init, peers=peers)
    assert joint.estimated and np.array_equal(joint.pairs, plain.pairs)
    assert _pose_error(joint.transform, trial.T_true) < 0.3
