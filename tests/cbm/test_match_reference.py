"""The matcher gives the stored results of the reference implementation on fixed seeds
(``match_reference.py`` says which cases and how they were made).

Pairs and counts must be identical. A transform may differ from the stored one by floating-point
rounding only (``ROUNDING``): numpy's and the BLAS's summation order changes between releases and
CPUs (numpy 2.4 moved a case by 4e-16 m), while any real change of the pairs moves it by centimetres."""
import numpy as np
import pytest

from .match_reference import DATA, cases, outcome

STORED = np.load(DATA)
CASES = list(cases())
ROUNDING = 1e-9
"""Largest difference of a stored transform's entries (metres, and cos / sin of the yaw) taken as rounding."""


def test_every_stored_case_is_still_generated():
    assert {name for name, *_ in CASES} == {key.split("/")[0] for key in STORED.files}


@pytest.mark.parametrize("case", CASES, ids=[case[0] for case in CASES])
def test_pairs_and_transform_are_identical_to_the_stored_ones(case):
    name, ego, cav, init, variant = case
    for key, value in outcome(ego, cav, init, variant).items():
        if value.dtype.kind == "f":
            np.testing.assert_allclose(value, STORED[f"{name}/{key}"], rtol=0, atol=ROUNDING, err_msg=f"{name}: {key}")
        else:
            np.testing.assert_array_equal(value, STORED[f"{name}/{key}"], err_msg=f"{name}: {key}")
