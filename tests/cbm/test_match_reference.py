"""The matcher gives the stored results of the reference implementation on fixed seeds
(``match_reference.py`` says which cases and how they were made)."""
import numpy as np
import pytest

from .match_reference import DATA, cases, outcome

STORED = np.load(DATA)
CASES = list(cases())


def test_every_stored_case_is_still_generated():
    assert {name for name, *_ in CASES} == {key.split("/")[0] for key in STORED.files}


@pytest.mark.parametrize("case", CASES, ids=[case[0] for case in CASES])
def test_pairs_and_transform_are_identical_to_the_stored_ones(case):
    name, ego, cav, init, variant = case
    for key, value in outcome(ego, cav, init, variant).items():
        np.testing.assert_array_equal(value, STORED[f"{name}/{key}"], err_msg=f"{name}: {key}")
