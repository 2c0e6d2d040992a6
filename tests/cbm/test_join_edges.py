"""The join's vote buffer grows before every query, also for a query whose window misses the grid
(regression: such a query wrote its head one past the buffer: an IndexError interpreted, the heap
corrupted compiled, then 'cannot assign slice of shape (1025,)')."""
import numpy as np

import loaders
from cbm import interpreted
from cbm.methods import METHODS
from evaluation.presets import default_preset
from evaluation.trials import frame_inputs


def test_a_query_beside_the_grid_after_a_full_buffer_writes_within_it():
    """The shipped log's frame 62 under the opv2v protocol, CBM without a prior: one of its turned
    guesses fills the first 1024 votes exactly before a query whose window lies beside the grid."""
    scenario = default_preset().scenario
    trial = frame_inputs(loaders.open("argoverse2")[62], "opv2v").build(
        type(scenario)(**{**scenario.__dict__, "protocol": "opv2v"}), seed=0)
    run = METHODS["cbm-no-prior"]
    with interpreted():
        plain = run(trial.ego_boxes, trial.cav_boxes, trial.init)
    compiled = run(trial.ego_boxes, trial.cav_boxes, trial.init)
    np.testing.assert_array_equal(compiled.pairs, plain.pairs)
    np.testing.assert_array_equal(compiled.transform, plain.transform)
