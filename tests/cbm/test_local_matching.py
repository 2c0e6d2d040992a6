"""The output-sensitive join and the candidate sets listed on demand agree with the reference's
candidate sets (eq. 8-9) and the released code's voting sets (``cbm.reference.candidate_sets``), on
every path of the join."""
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from cbm import CBMParams, reference, se2
from cbm.engine import candidate_sets
from cbm.engine.context import prepare
from cbm.engine.counting import counts_and_votes
from cbm.engine.selection import by_count_descending
from support.scenes import street_scene

from .conftest import NEVER

PATHS = {"one thread": dict(threads=1, every=NEVER), "groups apart": dict(threads=2, GROUPS_APART_FROM=0),
         "parts of a group": dict(threads=2, GROUP_PARTS_FROM=0)}
"""The join's paths, and the tuning that makes this small scene take each."""


@pytest.mark.parametrize("path", list(PATHS))
@pytest.mark.parametrize("heading", ["align", "fold"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_counts_members_and_votes_are_the_references(seed, heading, path, tuned):
    tuned(**PATHS[path])
    rng = np.random.default_rng(seed)
    world = street_scene(24, rng, extent=40.0)
    ego = world[rng.permutation(24)[:18]]
    cav = se2.apply_boxes(se2.make(2.0, -1.0, 0.05), world[rng.permutation(24)[:16]])
    cav[:, 6] += rng.choice([0.0, np.pi], len(cav))
    params = CBMParams(heading=heading, sigma2=4.0)
    ready = prepare(ego, cav, np.eye(3), heading)
    count2, parts = counts_and_votes(ready, params.sigma1_rad, params.sigma2, params.sigma3)
    L = candidate_sets(ready, params.sigma1_rad, params.sigma2, count2)
    agents = reference.agents(ego, cav, np.eye(3), heading)
    expected = reference.candidate_sets(agents, params.sigma1_rad, params.sigma2)
    np.testing.assert_array_equal(L.count, expected.sum(axis=(2, 3)).ravel())
    for anchor in np.flatnonzero(L.count):
        i, j = divmod(int(anchor), len(cav))
        np.testing.assert_array_equal(L.members(anchor), np.flatnonzero(expected[i, j]))
    voting = reference.candidate_sets(agents, params.sigma1_rad, params.sigma3)
    listed = np.zeros_like(voting).reshape(len(count2), -1)
    for part in parts:
        listed[part[0], part[1]] = True
    listed[np.flatnonzero(listed.any(axis=1)), np.flatnonzero(listed.any(axis=1))] = True
    np.testing.assert_array_equal(listed, voting.reshape(len(count2), -1))


@given(st.lists(st.integers(0, 6), max_size=60))
def test_visit_order_is_by_decreasing_size_then_by_id(counts):
    count = np.array(counts, dtype=np.int64)
    order = np.argsort(-count, kind="stable")
    np.testing.assert_array_equal(by_count_descending(count), order[count[order] > 0])
