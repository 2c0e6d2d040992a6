"""The members listed for one input and sigma1 are read again after a sigma2 edit, with the same
members in the same order as listing them anew (``cbm.local_matching.listing``)."""
import numpy as np
import pytest

from cbm import CBMParams
from cbm.local_matching import NO_LISTING, count_candidates, listed_into, listing, members_into
from cbm.reuse import Reuse, prepare

from .test_reuse import outcome, trial

SIGMA2_EDITS = [3.0, 2.0, 2.5, 4.0, 1.5, 4.0, 3.5]
"""A user dragging sigma2 down and up again."""


def kept_listing(reuse: Reuse):
    kept = next(iter(reuse._entries.values())).kept
    return kept["listing"][1]


@pytest.mark.parametrize("layout", ["street", "dense"])
def test_sigma2_edits_read_the_listing_and_give_the_results_of_a_fresh_match(layout):
    t, reuse = trial(layout, 2), Reuse()
    listed_at = []
    for sigma2 in SIGMA2_EDITS:
        with_reuse, without = outcome(t, CBMParams(sigma2=sigma2), reuse), outcome(t, CBMParams(sigma2=sigma2), None)
        for key in with_reuse:
            np.testing.assert_array_equal(with_reuse[key], without[key], err_msg=f"sigma2={sigma2}: {key}")
        listed_at.append(kept_listing(reuse).sigma2)
    assert listed_at == [3.0, 3.0, 3.0, 4.0, 4.0, 4.0, 4.0]
    assert np.count_nonzero(kept_listing(reuse).at >= 0) > 0


def candidate_sets(layout: str, sigma2: float, kept: dict | None):
    t = trial(layout, 3)
    params = CBMParams(sigma2=sigma2)
    ready = prepare(t.ego_boxes, t.cav_boxes, t.init, params.heading)
    sets, _ = count_candidates(ready.ego_context, ready.cav_context, ready.ego_heading, ready.signs,
                               params.sigma1_rad, sigma2, None, kept)
    return sets


def outputs(sets) -> tuple[np.ndarray, ...]:
    """Room for one listed set: pair ids, ego and CAV objects, distances."""
    room = sets.width + 1
    return np.empty(room, np.int64), np.empty(room, np.int64), np.empty(room, np.int64), np.empty(room)


def listed(sets, anchor: int, arguments: tuple) -> tuple[np.ndarray, ...]:
    """The pair ids, ego and CAV objects and distances ``listed_into`` gives for ``anchor``."""
    i, j = divmod(anchor, sets.signs.shape[1])
    found = outputs(sets)
    size = listed_into(i, j, sets.signs[i, j], sets.lookup, arguments, *found)
    return tuple(values[:size] for values in found)


def anew(sets, anchor: int) -> tuple[np.ndarray, ...]:
    """The same, listed by ``members_into`` at the sets' own sigma2."""
    i, j = divmod(anchor, sets.signs.shape[1])
    found = outputs(sets)
    size = members_into(i, j, sets.signs[i, j], *sets.lookup, *found)
    return tuple(values[:size] for values in found)


def assert_same_listing(sets, arguments: tuple) -> None:
    for anchor in np.flatnonzero(sets.count)[::7]:
        for got, expected in zip(listed(sets, int(anchor), arguments), anew(sets, int(anchor))):
            np.testing.assert_array_equal(got, expected, err_msg=f"anchor {anchor}")


@pytest.mark.parametrize("layout", ["street", "dense"])
def test_a_set_read_from_a_wider_listing_is_the_set_listed_anew(layout):
    kept = {}
    wide = candidate_sets(layout, 4.0, kept)
    assert_same_listing(wide, wide.listing.arguments())
    narrow = candidate_sets(layout, 2.0, kept)
    assert narrow.listing is wide.listing and narrow.listing.sigma2 == 4.0
    assert np.count_nonzero(narrow.listing.at >= 0) > 0
    assert_same_listing(narrow, narrow.listing.arguments())


def test_a_full_listing_lists_again_what_it_has_no_room_for(monkeypatch):
    monkeypatch.setattr(listing, "CAPACITY", 200)
    kept = {}
    wide = candidate_sets("street", 4.0, kept)
    assert_same_listing(wide, wide.listing.arguments())
    assert 0 < wide.listing.fill[0] <= 200
    narrow = candidate_sets("street", 2.5, kept)
    assert_same_listing(narrow, narrow.listing.arguments())


def test_without_kept_inputs_nothing_is_listed_to_keep():
    sets = candidate_sets("street", 3.0, None)
    assert sets.listing is None
    assert_same_listing(sets, NO_LISTING.arguments())
