"""Behaviour of cbm.match a user relies on: invariances, recovery, degenerate and bad input."""
import numpy as np
import pytest

from cbm import CBMParams, match, se2
from evaluation.metrics import evaluate
from evaluation.scenario import ScenarioParams, make_trial
from support.scenes import street_scene

pytestmark = pytest.mark.filterwarnings("error")


def sind_trial(n=40, seed=0, **scenario):
    rng = np.random.default_rng(seed)
    world = street_scene(n, rng)
    params = dict(eta=0.6, sigma_p=0.2, sigma_theta=2.0, seed=seed) | scenario
    return make_trial(world, np.arange(n), ScenarioParams(**params))


def matched_ids(trial, result):
    return {(trial.ego_ids[i], trial.cav_ids[j]) for i, j in result.pairs}


@pytest.mark.parametrize("seed", range(6))
def test_shuffling_either_list_gives_the_same_matched_objects(seed):
    trial = sind_trial(seed=seed)
    reference = matched_ids(trial, match(trial.ego_boxes, trial.cav_boxes, trial.init))
    rng = np.random.default_rng(100 + seed)
    pe, pc = rng.permutation(len(trial.ego_boxes)), rng.permutation(len(trial.cav_boxes))
    result = match(trial.ego_boxes[pe], trial.cav_boxes[pc], trial.init)
    shuffled = {(trial.ego_ids[pe][i], trial.cav_ids[pc][j]) for i, j in result.pairs}
    assert len(reference) >= 10
    assert shuffled == reference


def test_ties_between_identical_sets_do_not_depend_on_order():
    """A perfectly regular grid: many anchors with equal contexts and equal set sizes."""
    xs, ys = np.meshgrid(np.arange(5) * 8.0, np.arange(4) * 8.0)
    grid = np.zeros((20, 7))
    grid[:, 0], grid[:, 1], grid[:, 3:6] = xs.ravel(), ys.ravel(), (4.5, 1.9, 1.6)
    init = se2.make(1.0, -1.0, np.radians(2))
    cav = se2.apply_boxes(se2.inverse(init), grid)
    reference = match(grid, cav, init).pairs
    assert len(reference) == 20 and np.all(reference[:, 0] == reference[:, 1])
    rng = np.random.default_rng(3)
    for _ in range(3):
        pe, pc = rng.permutation(20), rng.permutation(20)
        pairs = match(grid[pe], cav[pc], init).pairs
        assert {(pe[i], pc[j]) for i, j in pairs} == {tuple(p) for p in reference}


@pytest.mark.parametrize("seed", range(4))
def test_moving_either_frame_rigidly_changes_nothing(seed):
    trial = sind_trial(seed=seed)
    base = match(trial.ego_boxes, trial.cav_boxes, trial.init)
    G = se2.make(-35.0, 12.0, 2.1)
    moved_ego = match(se2.apply_boxes(G, trial.ego_boxes), trial.cav_boxes, G @ trial.init)
    H = se2.make(8.0, -50.0, -1.3)
    moved_cav = match(trial.ego_boxes, se2.apply_boxes(H, trial.cav_boxes), trial.init @ se2.inverse(H))
    np.testing.assert_array_equal(moved_ego.pairs, base.pairs)
    np.testing.assert_array_equal(moved_cav.pairs, base.pairs)
    np.testing.assert_allclose(moved_ego.transform, G @ base.transform, atol=1e-6)
    np.testing.assert_allclose(moved_cav.transform, base.transform @ se2.inverse(H), atol=1e-6)


@pytest.mark.parametrize("seed", range(5))
def test_sind_protocol_at_mild_noise_is_recovered(seed):
    trial = sind_trial(n=50, seed=seed, eta=0.5, sigma_p=0.3, sigma_theta=3.0)
    metrics = evaluate(match(trial.ego_boxes, trial.cav_boxes, trial.init), trial)
    assert metrics.precision >= 0.95 and metrics.recall >= 0.9
    assert metrics.rte < 0.3 and metrics.rre < 0.5


def test_result_explains_itself():
    trial = sind_trial(seed=7)
    result = match(trial.ego_boxes, trial.cav_boxes, trial.init)
    assert result.estimated and result.anchor is not None
    assert tuple(result.anchor) in {tuple(p) for p in result.context_pairs}
    assert result.candidate_count >= result.consensus_count == len(result.context_pairs)
    assert 0 <= result.runner_up_count < result.consensus_count and result.margin > 0
    assert result.residuals.shape == (len(result.pairs),) and np.all(result.residuals < 1.5)
    assert set(result.timings) >= {"context", "local_matching", "consensus_selection", "estimate", "total"}
    np.testing.assert_allclose(result.correction @ trial.init, result.transform)
    assert len(set(result.pairs[:, 0])) == len(set(result.pairs[:, 1])) == len(result.pairs)


def test_consensus_switch_is_the_papers_ablation():
    trial = sind_trial(seed=4, sigma_p=0.6, sigma_theta=8.0, eta=0.4)
    on = match(trial.ego_boxes, trial.cav_boxes, trial.init, CBMParams(consensus=True))
    off = match(trial.ego_boxes, trial.cav_boxes, trial.init, CBMParams(consensus=False))
    assert off.consensus_count >= on.consensus_count


def test_align_heading_keeps_frames_that_fold_flips():
    """Objects just below 90 degrees cross it under a 3 degree init error: folding flips every
    CAV frame by pi and no anchor can match; aligning never flips a co-visible object's frame."""
    rng = np.random.default_rng(5)
    world = street_scene(24, rng)
    world[:, 6] = np.pi / 2 - 0.02
    trial = make_trial(world, np.arange(24), ScenarioParams(eta=1.0, flip_prob=0.0, localization="fixed",
                                                             loc_x=0.0, loc_y=0.0, loc_yaw=3.0))
    folded = match(trial.ego_boxes, trial.cav_boxes, trial.init, CBMParams(heading="fold"))
    aligned = match(trial.ego_boxes, trial.cav_boxes, trial.init, CBMParams(heading="align"))
    assert evaluate(aligned, trial).recall == 1.0
    assert len(folded.pairs) < 12


@pytest.mark.parametrize("n_ego,n_cav", [(0, 0), (0, 5), (5, 0), (1, 1), (1, 4), (2, 2), (2, 7)])
def test_few_objects_keep_init_and_say_so(n_ego, n_cav):
    rng = np.random.default_rng(0)
    init = se2.make(3.0, 3.0, np.radians(5))
    result = match(street_scene(n_ego, rng), street_scene(n_cav, rng), init)
    assert len(result.pairs) <= 2
    if len(result.pairs) < 2:
        assert not result.estimated
        np.testing.assert_array_equal(result.transform, init)
    assert result.pairs.shape[1] == 2


def test_coincident_objects_make_no_nan_and_no_warning():
    boxes = np.zeros((6, 7))
    boxes[:, 3:6] = (4.5, 1.9, 1.6)
    boxes[3:, 0] = 10.0
    result = match(boxes, boxes.copy(), np.eye(3))
    assert np.isfinite(result.transform).all()
    assert np.isfinite(result.residuals).all()


@pytest.mark.parametrize("heading", ["fold", "align"])
def test_headings_exactly_at_plus_minus_90_degrees(heading):
    rng = np.random.default_rng(8)
    world = street_scene(20, rng)
    world[:, 6] = np.where(np.arange(20) % 2 == 0, np.pi / 2, -np.pi / 2)
    result = match(world, world.copy(), np.eye(3), CBMParams(heading=heading))
    assert len(result.pairs) == 20 and np.all(result.pairs[:, 0] == result.pairs[:, 1])


@pytest.mark.parametrize("argument,kwargs,message", [
    ("ego_boxes", dict(ego_boxes=np.zeros((3, 6))), "ego_boxes must be an (N, 7)"),
    ("cav_boxes", dict(cav_boxes=np.full((2, 7), np.nan)), "cav_boxes must be finite; row 0"),
    ("ego_boxes", dict(ego_boxes=np.array([[0, 0, 0, 1, 1, 1, np.inf]])), "ego_boxes must be finite"),
    ("init", dict(init=np.eye(2)), "init must be a finite (3, 3)"),
    ("init", dict(init=np.diag([2.0, 1.0, 1.0])), "init must be a rigid SE(2)"),
    ("params", dict(params={"sigma1": 10}), "params must be a CBMParams"),
])
def test_bad_input_names_the_argument(argument, kwargs, message):
    call = dict(ego_boxes=np.zeros((0, 7)), cav_boxes=np.zeros((0, 7)), init=np.eye(3)) | kwargs
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        match(**call)


@pytest.mark.parametrize("field,value", [("sigma1", 0.0), ("sigma2", -1.0), ("sigma3", float("nan")),
                                         ("sigma1", 120.0), ("heading", "up"), ("consensus_rule", "vote")])
def test_bad_params_name_the_field(field, value):
    with pytest.raises(ValueError, match=f"CBMParams.{field}"):
        CBMParams(**{field: value})
