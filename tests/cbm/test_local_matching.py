"""The output-sensitive join and on-demand candidate sets agree with a direct enumeration of eq. 7-8."""
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from cbm import CBMParams, se2
from cbm.context import build_context, fold_heading, pair_signs
from cbm.local_matching import count_candidates, join
from cbm.selection import by_count_descending
from support.scenes import street_scene


def direct_sets(ego_context, cav_context, signs, n_ego, n_cav, sigma1, sigma2):
    """L_ij of every anchor by testing every quadruple (eq. 7-8), as sets of pair ids."""
    cos2 = math.cos(math.radians(sigma1)) ** 2
    sets = {}
    for u, (i, ip) in enumerate(zip(ego_context.anchor, ego_context.member)):
        z = ego_context.vectors[u]
        for v, (j, jp) in enumerate(zip(cav_context.anchor, cav_context.member)):
            w = signs[i, j] * cav_context.vectors[v]
            l1 = abs(z[0] - w[0]) + abs(z[1] - w[1])
            norms = (z @ z) * (w @ w)
            if l1 <= sigma2 and norms > 0 and (z @ w) ** 2 >= cos2 * norms:
                sets.setdefault(i * n_cav + j, {i * n_cav + j}).add(ip * n_cav + jp)
    return sets


THREADING = {"one thread": (2**62, 2**62), "groups apart": (0, 2**62), "parts of a group": (2**62, 0)}
"""The join's paths: (``GROUPS_APART_FROM``, ``PARALLEL_FROM``) that make this small scene take them."""


@pytest.mark.parametrize("threading", list(THREADING))
@pytest.mark.parametrize("heading", ["align", "fold"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_counts_and_members_equal_the_direct_enumeration(seed, heading, threading, monkeypatch):
    monkeypatch.setattr(join, "GROUPS_APART_FROM", THREADING[threading][0])
    monkeypatch.setattr(join, "PARALLEL_FROM", THREADING[threading][1])
    rng = np.random.default_rng(seed)
    world = street_scene(24, rng, extent=40.0)
    ego = world[rng.permutation(24)[:18]]
    cav = se2.apply_boxes(se2.make(2.0, -1.0, 0.05), world[rng.permutation(24)[:16]])
    cav[:, 6] += rng.choice([0.0, np.pi], len(cav))
    params = CBMParams(heading=heading, sigma2=4.0)
    ego_heading, cav_heading = fold_heading(ego[:, 6]), fold_heading(cav[:, 6])
    signs = pair_signs(ego_heading, cav_heading, heading)
    ego_context, cav_context = build_context(ego[:, :2], ego_heading), build_context(cav[:, :2], cav_heading)
    candidates, parts = count_candidates(ego_context, cav_context, ego_heading, signs, params.sigma1_rad,
                                         params.sigma2, params.sigma3)
    vote_anchor, vote_member = (np.concatenate([part[k] for part in parts]) for k in (0, 1))
    expected = direct_sets(ego_context, cav_context, signs, len(ego), len(cav), params.sigma1, params.sigma2)
    assert {a: int(c) for a, c in enumerate(candidates.count) if c} == {a: len(m) for a, m in expected.items()}
    for anchor, members in expected.items():
        assert set(candidates.members(anchor).tolist()) == members
    votes = direct_sets(ego_context, cav_context, signs, len(ego), len(cav), params.sigma1, params.sigma3)
    listed = {}
    for a, m in zip(vote_anchor.tolist(), vote_member.tolist()):
        listed.setdefault(a, {a}).add(m)
    assert listed == votes


@given(st.lists(st.integers(0, 6), max_size=60))
def test_visit_order_is_by_decreasing_size_then_by_id(counts):
    count = np.array(counts, dtype=np.int64)
    order = np.argsort(-count, kind="stable")
    np.testing.assert_array_equal(by_count_descending(count), order[count[order] > 0])
