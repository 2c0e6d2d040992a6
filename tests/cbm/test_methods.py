"""The method registry: one record per method, read by the app, the evaluation, sweeps and search."""
import dataclasses

import numpy as np
import pytest

from cbm import CBMParams, match
from cbm.methods import METHODS, method, run
from evaluation.scenario import ScenarioParams, make_trial
from support.scenes import street_scene


def trial():
    rng = np.random.default_rng(0)
    return make_trial(street_scene(30, rng), np.arange(30), ScenarioParams(eta=0.6, sigma_p=0.2, seed=0))


def test_every_record_is_complete_and_labels_are_unique():
    assert len({m.label for m in METHODS.values()}) == len(METHODS)
    for name, record in METHODS.items():
        assert record.name == name and dataclasses.is_dataclass(record.params)
        assert set(record.tunable) <= {f.name for f in dataclasses.fields(record.params)}
        assert record.params_key in METHODS


def test_the_ablation_is_cbm_with_consensus_forced_off_and_shares_cbms_parameters():
    ablation = METHODS["cbm-no-consensus"]
    assert ablation.params_key == "cbm" and "consensus" not in ablation.tunable and ablation.explains
    t = trial()
    asked = CBMParams(sigma2=2.5, consensus=True)
    expected = match(t.ego_boxes, t.cav_boxes, t.init, dataclasses.replace(asked, consensus=False))
    np.testing.assert_array_equal(ablation(t.ego_boxes, t.cav_boxes, t.init, asked).pairs, expected.pairs)


def test_inputs_reach_only_the_methods_that_take_them():
    t = trial()
    with pytest.raises(ValueError, match="true_pairs"):
        run("oracle", t.ego_boxes, t.cav_boxes, t.init)
    result = run("oracle", t.ego_boxes, t.cav_boxes, t.init, true_pairs=t.gt_pairs)
    np.testing.assert_array_equal(result.pairs, t.gt_pairs)
    labels = (np.zeros(len(t.ego_boxes)), np.zeros(len(t.cav_boxes)))
    run("icp", t.ego_boxes, t.cav_boxes, t.init, labels=labels, true_pairs=t.gt_pairs)


def test_unknown_names_and_foreign_parameters_are_refused():
    with pytest.raises(ValueError, match="method must be one of"):
        method("cbm-fast")
    with pytest.raises(TypeError, match="params of ricp must be RICPParams"):
        METHODS["ricp"].resolved(CBMParams())


def test_controls_are_the_parameters_that_act():
    cbm, ablation = METHODS["cbm"], METHODS["cbm-no-consensus"]
    assert {"sigma3", "consensus_rule", "refine_gate", "consensus"} <= set(cbm.controls(CBMParams()))
    assert not {"sigma3", "consensus_rule", "consensus"} & set(ablation.controls(CBMParams()))
    assert "refine_gate" not in cbm.controls(CBMParams(refine=False))
    assert METHODS["icp"].controls(METHODS["icp"].params()) == METHODS["icp"].tunable
