"""Local matching's join counts and lists exactly what the stored reference join did, on the street
and the dense layout (``join_reference.py`` says which cases and how they were made)."""
import numpy as np
import pytest

from .join_reference import DATA, cases, outcome

STORED = np.load(DATA)
CASES = list(cases())


def test_every_stored_case_is_still_generated():
    assert {name for name, *_ in CASES} == {key.split("/")[0] for key in STORED.files}


@pytest.mark.parametrize("case", CASES, ids=[case[0] for case in CASES])
def test_counts_and_voting_quadruples_are_identical_to_the_stored_ones(case):
    name, ego, cav, init, keywords = case
    for key, value in outcome(ego, cav, init, keywords).items():
        np.testing.assert_array_equal(value, STORED[f"{name}/{key}"], err_msg=f"{name}: {key}")
