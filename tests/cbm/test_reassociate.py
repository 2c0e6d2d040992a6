"""Guided re-association after CBM: a gated one-to-one assignment under the estimate, refitted until
the pairs settle, that adds the true pairs CBM's one-shot sets missed and never drifts away."""
import dataclasses

import numpy as np
import pytest

from cbm import CBMParams, match, se2
from cbm.engine import assignment as module
from cbm.engine.assignment import gated_assignment
from cbm.engine.interpreted import interpreted
from cbm.estimate import robust_fit
from cbm.reassociate import MAX_ROUNDS, reassociate
from evaluation.metric_registry import aggregate
from evaluation.metrics import evaluate, is_success
from evaluation.scenario import ScenarioParams, make_trial
from support.scenes import street_scene

pytestmark = pytest.mark.filterwarnings("error")
CAR = (4.5, 1.9, 1.6)
PEDESTRIAN = (0.6, 0.6, 1.7)


def boxes(xy, size=CAR, yaw=0.0):
    out = np.zeros((len(xy), 7))
    out[:, :2], out[:, 3:6], out[:, 6] = xy, size, yaw
    return out


def hard_trial(seed: int, n: int = 60):
    rng = np.random.default_rng(seed)
    world = street_scene(n, rng, extent=70.0)
    return make_trial(world, np.arange(n), ScenarioParams(eta=0.3, sigma_p=0.6, sigma_theta=10.0, seed=seed))


def test_assignment_is_one_to_one_inside_the_gate_and_undoes_a_swap():
    ego = boxes([[0.0, 0.0], [1.2, 0.0], [30.0, 0.0]])
    cav = boxes([[1.1, 0.2], [0.1, -0.1], [34.0, 0.0]])
    pairs = gated_assignment(ego, cav, gate=1.5, sigma=0.3)
    np.testing.assert_array_equal(pairs, [[0, 1], [1, 0]])


def test_a_flipped_heading_still_pairs_but_a_different_size_does_not():
    ego = boxes([[0.0, 0.0], [10.0, 0.0]])
    cav = np.concatenate([boxes([[0.2, 0.1]], yaw=np.pi), boxes([[10.2, 0.0]], size=PEDESTRIAN)])
    np.testing.assert_array_equal(gated_assignment(ego, cav, gate=1.0, sigma=0.3), [[0, 0]])


def test_degenerate_sizes_compare_without_warnings():
    ego = boxes([[0.0, 0.0], [10.0, 0.0]], size=(0.0, 0.0, 0.0))
    cav = boxes([[0.1, 0.0], [10.1, 0.0]], size=(0.0, 0.0, 0.0))
    np.testing.assert_array_equal(gated_assignment(ego, cav, gate=1.0, sigma=0.3), [[0, 0], [1, 1]])


def test_large_problems_split_into_groups_with_the_same_answer(monkeypatch):
    rng = np.random.default_rng(3)
    ego = boxes(rng.uniform(-40, 40, (120, 2)), yaw=rng.uniform(-np.pi, np.pi, 120)[:, None][:, 0])
    cav = ego.copy()
    cav[:, :2] += rng.normal(0, 0.8, (120, 2))
    dense = gated_assignment(ego, cav, gate=3.0, sigma=0.8)
    monkeypatch.setattr(module, "DENSE_BLOCK", 0)
    np.testing.assert_array_equal(gated_assignment(ego, cav, gate=3.0, sigma=0.8), dense)
    assert len(dense) > 100


@pytest.mark.parametrize("seed", range(4))
def test_groups_are_the_connected_components_of_the_candidates(seed):
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    rng = np.random.default_rng(seed)
    n_ego, n_cav = 40, 30
    candidates = np.unique(np.stack([rng.integers(0, n_ego, 25), rng.integers(0, n_cav, 25)], axis=1), axis=0)
    group, size = module.connected_groups(candidates[:, 0], candidates[:, 1], n_ego, n_cav)
    graph = coo_matrix((np.ones(len(candidates)), (candidates[:, 0], n_ego + candidates[:, 1])),
                       shape=(n_ego + n_cav,) * 2)
    expected = connected_components(graph, directed=False)[1][candidates[:, 0]]
    same, expected_same = group[:, None] == group[None, :], expected[:, None] == expected[None, :]
    np.testing.assert_array_equal(same, expected_same)
    np.testing.assert_array_equal(size, np.bincount(group))
    first = np.array([np.flatnonzero(group == g)[0] for g in range(len(size))])
    assert (np.diff(first) > 0).all() and len(size) > 5
    with interpreted():
        plain = module.connected_groups(candidates[:, 0], candidates[:, 1], n_ego, n_cav)
    np.testing.assert_array_equal(plain[0], group)
    np.testing.assert_array_equal(plain[1], size)


def test_each_groups_block_holds_its_candidates_costs_between_its_boxes_in_order():
    rng = np.random.default_rng(5)
    candidates = np.unique(np.stack([rng.integers(0, 40, 30), rng.integers(0, 30, 30)], axis=1), axis=0)
    cost = rng.uniform(0.0, 9.0, len(candidates))
    group, size = module.connected_groups(candidates[:, 0], candidates[:, 1], 40, 30)
    row_ids, row_at, col_ids, col_at, blocks, block_at = module.dense_blocks(
        candidates[:, 0], candidates[:, 1], cost, group, len(size), 40, 30, -1.0)
    for g in range(len(size)):
        mine = candidates[group == g]
        rows, row_of = np.unique(mine[:, 0], return_inverse=True)
        cols, col_of = np.unique(mine[:, 1], return_inverse=True)
        expected = np.full((len(rows), len(cols)), -1.0)
        expected[row_of, col_of] = cost[group == g]
        np.testing.assert_array_equal(row_ids[row_at[g]:row_at[g + 1]], rows)
        np.testing.assert_array_equal(col_ids[col_at[g]:col_at[g + 1]], cols)
        np.testing.assert_array_equal(blocks[block_at[g]:block_at[g + 1]].reshape(expected.shape), expected)
    assert (size > 2).any()


def kd_tree_pairs(ego, cav, gate, sigma):
    """``gated_pairs`` as it was built on scipy's k-d tree, sorted by (ego, CAV) index."""
    from scipy.spatial import cKDTree

    found = cKDTree(ego[:, :2]).sparse_distance_matrix(cKDTree(cav[:, :2]), gate, output_type="ndarray")
    i, j, d = found["i"].astype(np.intp), found["j"].astype(np.intp), found["v"]
    mismatch = module.size_mismatch(ego[i], cav[j])
    keep = mismatch <= module.SIZE_GATE
    i, j, d, mismatch = i[keep], j[keep], d[keep], mismatch[keep]
    cost = ((d / sigma) ** 2 + (module.axis_difference(ego[i, 6], cav[j, 6]) / module.HEADING_SIGMA) ** 2
            + (mismatch / module.SIZE_SIGMA) ** 2)
    order = np.lexsort((j, i))
    return np.stack([i, j], axis=1)[order], cost[order]


def random_scene(rng, n_ego, n_cav, on_grid):
    """Boxes on a 1 m grid (many centres exactly at the gate) or scattered near each other, with
    random headings and sizes from degenerate to twice a car's."""
    ego, cav = np.zeros((n_ego, 7)), np.zeros((n_cav, 7))
    if on_grid:
        ego[:, :2], cav[:, :2] = rng.integers(-4, 5, (n_ego, 2)), rng.integers(-4, 5, (n_cav, 2))
    else:
        ego[:, :2] = rng.uniform(-15, 15, (n_ego, 2))
        cav[:, :2] = rng.uniform(-15, 15, (n_cav, 2)) if n_ego == 0 else ego[rng.integers(0, n_ego, n_cav), :2]
        cav[:, :2] += rng.normal(0, 1.0, (n_cav, 2))
    ego[:, 3:6] = rng.choice([0.0, 1.9, 2.1, 4.5, 9.0], (n_ego, 3))
    cav[:, 3:6] = rng.choice([0.0, 1.9, 4.5], (n_cav, 3))
    ego[:, 6], cav[:, 6] = rng.uniform(-np.pi, np.pi, n_ego), rng.uniform(-np.pi, np.pi, n_cav)
    return ego, cav


@pytest.mark.parametrize("seed", range(6))
def test_gated_pairs_are_the_k_d_trees_to_the_last_bit(seed):
    rng = np.random.default_rng(seed)
    for n_ego, n_cav in [(0, 0), (0, 5), (5, 0), (1, 1), (1, 30), (30, 1), (40, 40), (300, 250)]:
        for on_grid, gate in [(True, 1.0), (True, 2.0), (True, np.sqrt(2.0)), (False, rng.uniform(0.5, 4.0))]:
            ego, cav = random_scene(rng, n_ego, n_cav, on_grid)
            expected = kd_tree_pairs(ego, cav, gate, gate / 3)
            found = module.gated_pairs(ego, cav, gate, gate / 3)
            np.testing.assert_array_equal(found[0].reshape(-1, 2), expected[0].reshape(-1, 2))
            np.testing.assert_array_equal(found[1], expected[1])
            with interpreted():
                plain = module.gated_pairs(ego, cav, gate, gate / 3)
            np.testing.assert_array_equal(plain[0], found[0])
            np.testing.assert_array_equal(plain[1], found[1])


@pytest.mark.parametrize("seed", range(4))
def test_groups_whose_rows_take_their_own_least_cost_are_answered_as_the_solver_does(seed):
    """``row_minima`` against ``linear_sum_assignment`` of each group's dense block, on groups wide
    and tall, sparse and full, with costs drawn from few values (ties) or many: whenever it
    answers a group, the solver agrees; the lone candidates are always answered."""
    from scipy.optimize import linear_sum_assignment

    rng = np.random.default_rng(seed)
    answered = 0
    for case in range(300):
        n_ego, n_cav = rng.integers(1, 12, 2)
        candidates = np.unique(np.stack([rng.integers(0, n_ego, 12), rng.integers(0, n_cav, 12)], axis=1), axis=0)
        few = rng.random() < 0.3
        cost = rng.choice([0.0, 1.0, 2.0, 3.5], len(candidates)) if few else rng.uniform(0.0, 30.0, len(candidates))
        rows, cols = candidates[:, 0], candidates[:, 1]
        group, size = module.connected_groups(rows, cols, n_ego, n_cav)
        if rng.random() < 0.5:
            group, size = np.zeros(len(rows), np.int64), np.array([len(rows)])
        partner, solved = module.row_minima(rows, cols, cost, group, len(size), n_ego, n_cav, 1e6)
        for g in np.flatnonzero(solved):
            mine = candidates[group == g]
            ego_ids, r_of = np.unique(mine[:, 0], return_inverse=True)
            cav_ids, c_of = np.unique(mine[:, 1], return_inverse=True)
            block = np.full((len(ego_ids), len(cav_ids)), 1e6)
            block[r_of, c_of] = cost[group == g]
            r, c = linear_sum_assignment(block)
            np.testing.assert_array_equal(partner[ego_ids], _partners(ego_ids, cav_ids[c], ego_ids[r]))
            answered += size[g] > 1
        assert solved[size == 1].all()
        if case < 20:
            with interpreted():
                plain = module.row_minima(rows, cols, cost, group, len(size), n_ego, n_cav, 1e6)
            np.testing.assert_array_equal(plain[0], partner)
            np.testing.assert_array_equal(plain[1], solved)
    assert answered > 50


def _partners(ego_ids, cav_of, paired):
    """Each of ``ego_ids``'s CAV partner (-1 if unpaired) given the ``paired`` ego ids' ``cav_of``."""
    out = np.full(len(ego_ids), -1)
    out[np.searchsorted(ego_ids, paired)] = cav_of
    return out


def test_refinement_adds_true_pairs_cbm_missed():
    own, refined, kept, right = [], [], 0, 0
    for seed in range(8):
        trial = hard_trial(seed)
        result = match(trial.ego_boxes, trial.cav_boxes, trial.init)
        truth = {tuple(p) for p in trial.gt_pairs.tolist()}
        own_right = {tuple(p) for p in result.context_pairs.tolist()} & truth
        right += len(own_right)
        kept += len(own_right & {tuple(p) for p in result.pairs.tolist()})
        own.append(evaluate(dataclasses.replace(result, pairs=result.context_pairs), trial))
        refined.append(evaluate(result, trial))
    before, after = aggregate(own), aggregate(refined)
    assert after["recall"] >= before["recall"] + 0.1
    assert after["precision"] >= before["precision"] - 0.02
    assert kept >= 0.95 * right


def test_refinement_makes_hard_noise_succeed_more_often():
    trials = [hard_trial(seed) for seed in range(12)]
    def successes(params):
        return sum(is_success(evaluate(match(t.ego_boxes, t.cav_boxes, t.init, params), t)) for t in trials)
    assert successes(CBMParams()) >= successes(CBMParams(refine=False)) + 1
    assert successes(CBMParams()) >= 10


def test_switched_off_the_pairs_are_cbms_own():
    trial = hard_trial(0)
    result = match(trial.ego_boxes, trial.cav_boxes, trial.init, CBMParams(refine=False))
    np.testing.assert_array_equal(result.pairs, result.context_pairs)
    assert "reassociate" not in result.timings


def test_a_refinement_with_less_support_keeps_cbms_answer():
    """Under a pose 2 m off, only two decoy CAV boxes fall inside the gate: two pairs are fewer
    than CBM's five, so CBM's answer stands."""
    rng = np.random.default_rng(5)
    ego = boxes(rng.uniform(-30, 30, (5, 2)))
    cav = np.concatenate([ego, boxes(ego[:2, :2] - (2.0, 0.0))])
    pairs = np.stack([np.arange(5), np.arange(5)], axis=1)
    refit = lambda s, d: robust_fit(s, d, 0.3)  # noqa: E731
    off = dataclasses.replace(refit(cav[:5, :2], ego[:, :2]), transform=se2.make(2.0, 0.0, 0.0))
    refined = reassociate(ego, cav, pairs, off, 3.5, refit)
    assert not refined.accepted and refined.fit is off
    np.testing.assert_array_equal(refined.pairs, pairs)


def test_rounds_are_bounded_and_stop_when_the_pairs_settle():
    trial = hard_trial(0)
    cbm = match(trial.ego_boxes, trial.cav_boxes, trial.init, CBMParams(refine=False))
    assert len(cbm.pairs) < len(trial.gt_pairs)
    cav = se2.apply_boxes(trial.init, trial.cav_boxes)
    refit = lambda s, d: robust_fit(s, d, 0.3)  # noqa: E731
    fit = refit(cav[cbm.pairs[:, 1], :2], trial.ego_boxes[cbm.pairs[:, 0], :2])
    refined = reassociate(trial.ego_boxes, cav, cbm.pairs, fit, 3.5, refit)
    assert 2 <= refined.rounds <= MAX_ROUNDS
    again = reassociate(trial.ego_boxes, cav, refined.pairs, refined.fit, 3.5, refit)
    assert again.rounds == 1
    np.testing.assert_array_equal(again.pairs, refined.pairs)


@pytest.mark.parametrize("bad", [dict(refine_gate=0.0), dict(refine_gate=float("nan")), dict(refine="yes"),
                                 dict(estimator="svd")])
def test_bad_parameters_are_named(bad):
    name = next(iter(bad))
    with pytest.raises(ValueError, match=f"CBMParams.{name}"):
        CBMParams(**bad)
