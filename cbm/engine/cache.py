"""What a threshold edit does not change, kept per input: an interactive sigma1 / sigma2 / sigma3
edit recomputes only the join and what follows it, and only the join's pass the edit changed.

``EditCache`` wraps local matching from outside: per input (the boxes, the initial pose and the
heading mode) it keeps steps 1-3 (``cbm.engine.context.Prepared``), the join's grids and both agents'
sorted blocks, and each result keyed by exactly the thresholds it depends on: card(L_ij) by
(sigma1, sigma2), the voting sets by (sigma1, sigma3). So a sigma2 edit counts without listing
the votes, a sigma3 edit lists the votes without counting, a sigma1 edit does both. Two caches
serve a sigma2 edit, keyed by sigma1: the quadruples' L1 distances (``cbm.engine.distances``), from
which card(L_ij) at any smaller sigma2 is counted without a join, and the candidate sets' members
listed so far (``cbm.engine.listing.Listing``), which the selection reads again instead of listing
them (each measured in docs/benchmarks.md). A change of noise or frame changes the boxes: a new
input. ``Reuse`` keeps the ``FRAMES`` inputs used last (fewer when they hold more than ``MOST_BYTES``).
"""
from __future__ import annotations

import hashlib
import threading
from collections import Counter, OrderedDict
from dataclasses import dataclass, field
from typing import Generic, TypeVar

import numpy as np

from .candidates import SortedBlocks
from .context import Prepared, prepare
from .counting import counts_and_votes
from .distances import HEADROOM, Distances, counted, distances_within
from .join import Grids
from .listing import CandidateSets, Listing, both_blocks, candidate_sets, new_listing
from .threads import TRIM_FROM, check_stop, stop_flag, trim_freed
from .voting import PairSets, voted_by_member

T = TypeVar("T")

FRAMES = 4
"""Inputs kept: the frame on screen and the few the user stepped through last."""
MOST_BYTES = 256 * 2**20
"""Memory the kept inputs may hold (a grid at 1000 objects per agent is tens of MB): past it the
least recently used go, down to the latest one."""


@dataclass
class Keyed(Generic[T]):
    """One value kept with the thresholds it was computed for; asking with others finds nothing."""

    key: tuple | None = None
    value: T | None = None

    def get(self, key: tuple) -> T | None:
        return self.value if self.key == key else None

    def put(self, key: tuple, value: T) -> T:
        self.key, self.value = key, value
        return value


@dataclass
class EditCache:
    """Local matching of one input, kept for the next threshold edit (see the module)."""

    prepared: Prepared
    grids: Grids = field(default_factory=Grids)
    blocks: tuple[SortedBlocks, SortedBlocks] | None = None
    counts: Keyed[np.ndarray] = field(default_factory=Keyed)
    """card(L_ij) + 1 of every anchor with a candidate, by (sigma1, sigma2)."""
    voting: Keyed[PairSets] = field(default_factory=Keyed)
    """The voting sets by member, by (sigma1, sigma3)."""
    distances: Keyed[Distances] = field(default_factory=Keyed)
    """Every accepted quadruple's anchor pair and L1 distance, by sigma1, up to a radius."""
    listing: Keyed[Listing] = field(default_factory=Keyed)
    """The members listed so far, by sigma1, at the largest sigma2 asked for."""
    passes: Counter = field(default_factory=Counter)
    """How often card(L_ij) was counted (``"count"``), the votes listed (``"votes"``) and the
    distances kept (``"distances"``) on this input."""

    def local_matching(self, sigma1_rad: float, sigma2: float, sigma3: float | None) -> tuple[np.ndarray, PairSets]:
        """card(L_ij) at sigma2 and the voting sets at sigma3 (empty when ``sigma3`` is None: no
        consensus), from what is kept, the join running only the passes missing."""
        n_pairs = self.prepared.signs.size
        count2 = self.counts.get((sigma1_rad, sigma2))
        if count2 is None:
            count2 = self._count_of_a_sigma2_edit(sigma1_rad, sigma2)
        voted_by = PairSets.empty(n_pairs) if sigma3 is None else self.voting.get((sigma1_rad, sigma3))
        counted, votes = counts_and_votes(self.prepared, sigma1_rad, sigma2, sigma3, counting=count2 is None,
                                          listing=voted_by is None, grids=self.grids)
        if count2 is None:
            self.passes["count"] += 1
            count2 = self.counts.put((sigma1_rad, sigma2), counted)
        if voted_by is None:
            self.passes["votes"] += 1
            voted_by = self.voting.put((sigma1_rad, sigma3), voted_by_member(votes, n_pairs))
        return count2, voted_by

    def _count_of_a_sigma2_edit(self, sigma1_rad: float, sigma2: float) -> np.ndarray | None:
        """card(L_ij) + 1 at ``sigma2`` counted from the quadruples' distances kept for this sigma1,
        kept here at ``HEADROOM`` times sigma2 when this is a sigma2 edit (the counts kept are for
        this sigma1 and another sigma2); None when the join must count: a first count, a sigma1
        edit, or too many quadruples."""
        found = self.distances.get((sigma1_rad,))
        if found is None or (found.anchor is not None and found.radius < sigma2):
            if self.counts.key is None or self.counts.key[0] != sigma1_rad:
                return None
            found = distances_within(self.prepared, sigma1_rad, HEADROOM * sigma2, self.grids)
            self.distances.put((sigma1_rad,), found)
            self.passes["distances"] += 1
        if found.anchor is None:
            return None
        self.passes["count"] += 1
        return self.counts.put((sigma1_rad, sigma2), counted(found, sigma2, self.prepared.signs.size))

    def candidate_sets(self, sigma1_rad: float, sigma2: float, count2: np.ndarray) -> CandidateSets:
        """L_ij of every anchor, with the sorted blocks kept and the listing kept for this sigma1
        when it was listed at a sigma2 of at least this one (else a new one, kept)."""
        if self.blocks is None:
            self.blocks = both_blocks(self.prepared)
        listing = self.listing.get((sigma1_rad,))
        if listing is None or listing.sigma2 < sigma2:
            listing = self.listing.put((sigma1_rad,), new_listing(sigma2, count2))
        return candidate_sets(self.prepared, sigma1_rad, sigma2, count2, self.blocks, listing)


class Reuse:
    """The ``EditCache`` of the ``frames`` inputs used last, least recently used out, and fewer when
    they hold more than ``most_bytes``; safe to share between threads (two threads asking for a
    new input at once may both build it)."""

    def __init__(self, frames: int = FRAMES, most_bytes: int = MOST_BYTES) -> None:
        self.frames, self.most_bytes = frames, most_bytes
        self.hits = self.misses = 0
        self._entries: OrderedDict[bytes, EditCache] = OrderedDict()
        self._lock = threading.Lock()

    def __len__(self) -> int:
        return len(self._entries)

    def cache(self, ego: np.ndarray, cav: np.ndarray, init: np.ndarray, heading: str) -> EditCache:
        """The kept cache of this input, or a new one (kept, dropping the oldest past ``frames``)."""
        key = _key(ego, cav, init, heading)
        with self._lock:
            found = self._entries.get(key)
            if found is not None:
                self._entries.move_to_end(key)
                self.hits += 1
                self._trim()
                return found
            self.misses += 1
        made = EditCache(prepare(ego, cav, init, heading, stop_flag()))
        check_stop()
        with self._lock:
            self._entries[key] = made
            self._trim()
        return made

    def _trim(self) -> None:
        """Forget the least recently used inputs past ``frames`` or ``most_bytes`` (what the
        earlier calls' joins added counts), keeping the latest; called under the lock. Freed
        memory past ``threads.TRIM_FROM`` goes back to the system."""
        freed = 0
        while len(self._entries) > self.frames or (len(self._entries) > 1 and self.nbytes() > self.most_bytes):
            freed += _nbytes(self._entries.popitem(last=False)[1])
        if freed >= TRIM_FROM:
            trim_freed()

    def clear(self) -> None:
        """Forget every kept input (no tab needs them any more) and hand the memory back."""
        with self._lock:
            self._entries.clear()
        trim_freed()

    def nbytes(self) -> int:
        """The bytes of every array the kept inputs hold (what local matching added to them too)."""
        return sum(_nbytes(entry) for entry in list(self._entries.values()))


def _nbytes(value) -> int:
    """The bytes of the arrays in ``value``: an array, a dataclass, a dict, a list or tuple of them."""
    if isinstance(value, np.ndarray):
        return value.nbytes
    if isinstance(value, dict):
        return sum(_nbytes(v) for v in list(value.values()))
    if isinstance(value, (list, tuple)):
        return sum(_nbytes(v) for v in value)
    if hasattr(value, "__dataclass_fields__"):
        return sum(_nbytes(getattr(value, name)) for name in value.__dataclass_fields__)
    return 0


def _key(ego: np.ndarray, cav: np.ndarray, init: np.ndarray, heading: str) -> bytes:
    """A digest of everything ``prepare`` reads."""
    digest = hashlib.blake2b(heading.encode(), digest_size=20)
    for values in (ego, cav, init):
        values = np.ascontiguousarray(values, np.float64)
        digest.update(str(values.shape).encode())
        digest.update(values.tobytes())
    return digest.digest()
