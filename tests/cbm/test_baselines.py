"""The paper's baselines (cbm.baselines): ICP, RICP and VIPS on synthetic scenes with known truth."""
from __future__ import annotations

import numpy as np
import pytest

from cbm import se2
from cbm.baselines import ICPParams, RICPParams, V2XRegParams, VIPSParams
from cbm.estimate import weighted_procrustes
from cbm.methods import METHODS, run
from cbm.result import MatchResult

NAMES = ["icp", "ricp", "vips", "v2xregpp", "freealign"]
FEWEST_PAIRS = {"v2xregpp": 1}
"""Pairs a method needs for an estimate: two centres, or one box's corners (V2X-Reg++)."""
WIDE = {"v2xregpp": V2XRegParams(top_k=100)}
"""Parameters under which a method may pair every object (V2X-Reg++ keeps 10 boxes per agent by default)."""


def spaced_points(rng: np.random.Generator, n: int, half: float, min_gap: float) -> np.ndarray:
    """``n`` points uniform in the square [-half, half]^2, pairwise at least ``min_gap`` apart."""
    points: list[np.ndarray] = []
    while len(points) < n:
        p = rng.uniform(-half, half, 2)
        if all(np.hypot(*(p - q)) >= min_gap for q in points):
            points.append(p)
    return np.array(points)


def make_scene(seed: int, n: int = 30, covisible: float = 1.0, half: float = 30.0, min_gap: float = 4.0,
               error: tuple[float, float, float] = (0.5, 0.5, 1.0), sigma_p: float = 0.05,
               sigma_yaw_deg: float = 1.0, flip: float = 0.0):
    """Ego boxes, CAV boxes, init, the true CAV->ego transform and the true pairs.

    ``round(covisible * n)`` objects are seen by both agents, the rest split between them; every
    detection gets Gaussian position and heading noise and, with probability ``flip``, a heading turned
    by pi. ``init = E @ T_true`` with the ego-frame error ``E = make(*error)`` (yaw in degrees).
    Both box arrays are shuffled.
    """
    rng = np.random.default_rng(seed)
    xy = spaced_points(rng, n, half, min_gap)
    sizes = np.column_stack([rng.uniform(3.5, 5.0, n), rng.uniform(1.6, 2.0, n), rng.uniform(1.4, 1.8, n)])
    world = np.column_stack([xy, np.zeros(n), sizes, rng.uniform(-np.pi, np.pi, n)])
    T_true = se2.make(rng.uniform(-20, 20), rng.uniform(-20, 20), rng.uniform(-np.pi, np.pi))
    order = rng.permutation(n)
    n_co = int(round(covisible * n))
    shared, rest = order[:n_co], order[n_co:]
    ego_ids = rng.permutation(np.r_[shared, rest[: len(rest) // 2]])
    cav_ids = rng.permutation(np.r_[shared, rest[len(rest) // 2:]])

    def detect(boxes: np.ndarray) -> np.ndarray:
        out = boxes.copy()
        out[:, :2] += rng.normal(0.0, sigma_p, (len(out), 2))
        out[:, 6] += rng.normal(0.0, np.radians(sigma_yaw_deg), len(out)) + np.pi * (rng.random(len(out)) < flip)
        return out

    ego = detect(world[ego_ids])
    cav = detect(se2.apply_boxes(se2.inverse(T_true), world[cav_ids]))
    init = se2.make(error[0], error[1], np.radians(error[2])) @ T_true
    cav_index = {obj: k for k, obj in enumerate(cav_ids)}
    truth = {(i, cav_index[obj]) for i, obj in enumerate(ego_ids) if obj in cav_index}
    return ego, cav, init, T_true, truth


def precision_recall_rte(result: MatchResult, truth: set, T_true: np.ndarray) -> tuple[float, float, float]:
    got = {tuple(p) for p in result.pairs.tolist()}
    hits = len(got & truth)
    precision = hits / len(got) if got else 0.0
    rte = float(np.linalg.norm(se2.translation_of(result.transform) - se2.translation_of(T_true)))
    return precision, hits / len(truth), rte


def matched_set(result: MatchResult, ego_ids: np.ndarray, cav_ids: np.ndarray) -> set:
    """The matched pairs as (ego id, CAV id), ``ego_ids[i]`` naming ego box i."""
    return {(int(ego_ids[i]), int(cav_ids[j])) for i, j in result.pairs.tolist()}


# --- behaviour on scenes with known outcome ----------------------------------------------------------


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_each_method_succeeds_with_small_initial_error(name: str, seed: int) -> None:
    ego, cav, init, T_true, truth = make_scene(seed)
    result = run(name, ego, cav, init, WIDE.get(name))
    precision, recall, rte = precision_recall_rte(result, truth, T_true)
    assert result.estimated
    assert precision >= 0.9 and recall >= 0.9
    assert rte < 0.3


def test_icp_fails_when_nearest_neighbours_are_wrong() -> None:
    """3 m / 3 m / 25 degrees: the closest points under init are mostly other objects."""
    scenes = [make_scene(seed, error=(3.0, 3.0, 25.0)) for seed in range(5)]
    precisions = [precision_recall_rte(run("icp", e, c, i), truth, T)[0] for e, c, i, T, truth in scenes]
    assert np.mean(precisions) < 0.4


@pytest.mark.parametrize("seed", range(5))
def test_vips_and_ricp_succeed_with_large_translation_error(seed: int) -> None:
    ego, cav, init, T_true, truth = make_scene(seed, half=25.0, error=(5.0, -5.0, 2.0))
    for name in ("vips", "ricp"):
        precision, recall, rte = precision_recall_rte(run(name, ego, cav, init), truth, T_true)
        assert precision >= 0.9 and recall >= 0.9 and rte < 0.3, name


def test_icp_fails_with_large_translation_error() -> None:
    scenes = [make_scene(seed, half=25.0, error=(5.0, -5.0, 2.0)) for seed in range(5)]
    precisions = [precision_recall_rte(run("icp", e, c, i), truth, T)[0] for e, c, i, T, truth in scenes]
    assert np.mean(precisions) < 0.5


def test_vips_uses_categories_when_given() -> None:
    ego, cav, init, T_true, truth = make_scene(3)
    ego_labels = np.zeros(len(ego), dtype=int)
    matched = run("vips", ego, cav, init, labels=(ego_labels, np.zeros(len(cav), dtype=int)))
    assert precision_recall_rte(matched, truth, T_true)[0] >= 0.9
    apart = run("vips", ego, cav, init, labels=(ego_labels, np.ones(len(cav), dtype=int)))
    assert len(apart.pairs) == 0 and not apart.estimated


def test_ricp_anderson_acceleration_reaches_the_same_answer() -> None:
    ego, cav, init, _, _ = make_scene(4, covisible=0.6, error=(3.0, 3.0, 5.0), sigma_p=0.3, flip=0.5)
    fast = run("ricp", ego, cav, init, RICPParams(anderson=True))
    plain = run("ricp", ego, cav, init, RICPParams(anderson=False))
    np.testing.assert_array_equal(fast.pairs, plain.pairs)
    np.testing.assert_allclose(fast.transform, plain.transform, atol=1e-4)


# --- order invariance ----------------------------------------------------------------------------------


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("seed", [5, 6])
def test_matched_set_does_not_depend_on_input_order(name: str, seed: int) -> None:
    ego, cav, init, _, _ = make_scene(seed, covisible=0.6, error=(3.0, 3.0, 5.0), sigma_p=0.3,
                                      sigma_yaw_deg=3.0, flip=0.5)
    rng = np.random.default_rng(seed + 100)
    pe, pc = rng.permutation(len(ego)), rng.permutation(len(cav))
    straight = run(name, ego, cav, init)
    shuffled = run(name, ego[pe], cav[pc], init)
    assert straight.estimated
    assert matched_set(straight, np.arange(len(ego)), np.arange(len(cav))) == matched_set(shuffled, pe, pc)
    np.testing.assert_allclose(straight.transform, shuffled.transform, atol=1e-9)


# --- the MatchResult contract --------------------------------------------------------------------------


@pytest.mark.parametrize("name", NAMES)
def test_result_is_one_to_one_sorted_and_self_consistent(name: str) -> None:
    ego, cav, init, _, _ = make_scene(7, covisible=0.7, error=(2.0, -1.0, 3.0), sigma_p=0.2)
    result = run(name, ego, cav, init)
    pairs = result.pairs
    assert pairs.dtype.kind == "i" and pairs.shape[1] == 2
    assert len(np.unique(pairs[:, 0])) == len(pairs) == len(np.unique(pairs[:, 1]))
    assert np.all(np.diff(pairs[:, 0]) > 0)
    moved = se2.apply_points(result.transform, cav[pairs[:, 1], :2])
    np.testing.assert_allclose(result.residuals, np.linalg.norm(ego[pairs[:, 0], :2] - moved, axis=1))
    np.testing.assert_allclose(result.correction @ result.init, result.transform, atol=1e-12)
    np.testing.assert_array_equal(result.init, init)
    assert result.anchor is None and result.runner_up_count == 0
    assert result.candidate_count == result.consensus_count == len(pairs)
    assert result.timings["total"] >= 0.0


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("n_ego, n_cav", [(0, 0), (1, 1), (0, 5), (5, 1)])
def test_fewer_than_two_objects_keeps_init(name: str, n_ego: int, n_cav: int) -> None:
    ego, cav, init, _, _ = make_scene(8, n=6)
    result = run(name, ego[:n_ego], cav[:n_cav], init)
    assert not result.estimated
    np.testing.assert_array_equal(result.transform, init)
    assert len(result.pairs) <= 1 and len(result.residuals) == len(result.pairs)


@pytest.mark.parametrize("name", NAMES)
def test_small_and_degenerate_inputs_never_break_the_contract(name: str) -> None:
    """Random 0-6 objects per agent, some spread over 0 m (coincident centres): no error, finite output."""
    rng = np.random.default_rng(11)
    for _ in range(40):
        n_ego, n_cav = rng.integers(0, 7, 2)
        spread = rng.choice([0.0, 1.0, 30.0])
        ego, cav = (np.column_stack([rng.uniform(-spread, spread, (n, 2)), np.zeros(n), np.full((n, 3), 2.0),
                                     rng.uniform(-3, 3, n)]) for n in (n_ego, n_cav))
        init = se2.make(*rng.normal(0.0, 3.0, 3))
        result = run(name, ego, cav, init)
        assert np.all(np.isfinite(result.transform)) and np.all(np.isfinite(result.residuals))
        assert result.estimated == (len(result.pairs) >= FEWEST_PAIRS.get(name, 2))
        if not result.estimated:
            np.testing.assert_array_equal(result.transform, init)


# --- input and parameter validation ----------------------------------------------------------------------


def _bad_inputs():
    ego, cav, init, _, _ = make_scene(9, n=8)
    nan_cav = cav.copy()
    nan_cav[2, 0] = np.nan
    return [
        ("ego_boxes", (ego[:, :6], cav, init)),
        ("cav_boxes", (ego, nan_cav, init)),
        ("ego_boxes", (ego[0], cav, init)),
        ("init", (ego, cav, init[:2])),
        ("init", (ego, cav, 2.0 * init)),
        ("init", (ego, cav, np.where(np.eye(3) > 0, np.inf, init))),
    ]


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("argument, args", _bad_inputs())
def test_bad_input_raises_value_error_naming_the_argument(name: str, argument: str, args: tuple) -> None:
    with pytest.raises(ValueError, match=argument):
        run(name, *args)


def test_vips_labels_must_match_their_boxes() -> None:
    ego, cav, init, _, _ = make_scene(9, n=8)
    with pytest.raises(ValueError, match="cav_labels"):
        run("vips", ego, cav, init, labels=(np.zeros(len(ego)), np.zeros(len(cav) + 1)))


@pytest.mark.parametrize("cls, field, value", [
    (ICPParams, "max_iterations", 0),
    (ICPParams, "tolerance", -1e-3),
    (ICPParams, "max_correspondence_distance", float("nan")),
    (RICPParams, "nu_alpha", 1.0),
    (RICPParams, "nu_end_k", 0.0),
    (RICPParams, "anderson_m", 2.5),
    (VIPSParams, "top_k", 0),
    (VIPSParams, "edge_gate", float("inf")),
    (VIPSParams, "score_threshold", 0.0),
])
def test_bad_parameters_raise_value_error_naming_the_field(cls: type, field: str, value: object) -> None:
    with pytest.raises(ValueError, match=field):
        cls(**{field: value})


def test_registry_runs_each_method_with_its_defaults() -> None:
    assert set(METHODS) == set(NAMES) | {"cbm", "cbm-no-consensus", "cbm-graph", "cbm-time", "cbm-smooth",
                                         "cbm-no-prior", "none", "oracle"}
    ego, cav, init, _, pairs = make_scene(0, n=10)
    for name, method in METHODS.items():
        truth = {"true_pairs": np.array(sorted(pairs))} if method.takes_truth else {}
        assert isinstance(run(name, ego, cav, init, method.params(), **truth), MatchResult)
    with pytest.raises(ValueError, match="method"):
        run("cmb", ego, cav, init)
    with pytest.raises(TypeError, match="params"):
        run("icp", ego, cav, init, VIPSParams())


def test_cbm_without_consensus_is_cbm_with_the_switch_off() -> None:
    from cbm import CBMParams, match

    ego, cav, init, _, _ = make_scene(3, n=30)
    params = CBMParams(sigma2=4.0)
    ablation = run("cbm-no-consensus", ego, cav, init, params)
    np.testing.assert_array_equal(ablation.pairs, match(ego, cav, init, CBMParams(sigma2=4.0, consensus=False)).pairs)


# --- the shared Procrustes fit ----------------------------------------------------------------------------


def test_weighted_procrustes_recovers_a_transform_and_ignores_zero_weights() -> None:
    rng = np.random.default_rng(10)
    src = rng.uniform(-20, 20, (12, 2))
    T = se2.make(3.0, -4.0, 2.5)
    dst = se2.apply_points(T, src)
    np.testing.assert_allclose(weighted_procrustes(src, dst), T, atol=1e-12)
    dst[0] += 50.0
    weights = np.r_[0.0, rng.uniform(0.5, 2.0, 11)]
    np.testing.assert_allclose(weighted_procrustes(src, dst, weights), T, atol=1e-12)
    with pytest.raises(ValueError, match="weights"):
        weighted_procrustes(src, dst, np.r_[1.0, np.zeros(11)])
