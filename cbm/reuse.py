"""What CBM built for one input that the thresholds of eq. 7-10 do not change, kept for the next
call on the same input: an interactive sigma1 / sigma2 / sigma3 edit recomputes only the join and
what follows it.

Per input (the boxes, the initial pose and the heading mode; ``Prepared``): steps 1-2 (the CAV boxes
in the ego frame, folded headings, the signs of eq. 6's frames), the context vectors of eq. 5-6,
the sorted blocks that list candidate sets, and the grids of the join for the latest search radius;
and, each keyed by exactly the thresholds it depends on, the latest card(L_ij) (sigma1, sigma2) and
the latest voting sets (sigma1, sigma3): a sigma2 edit counts again without listing the votes, a
sigma3 edit lists the votes without counting, a sigma1 edit does both (``recall``, ``remember``).
A change of noise or frame changes the boxes, so it is a new input. ``Reuse`` keeps the ``FRAMES``
inputs used last (fewer when they hold more than ``MOST_BYTES``) and forgets the least recently
used one.
"""
from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np

from . import se2
from .context import Context, build_context, fold_heading, pair_signs

FRAMES = 4
"""Inputs kept: the frame on screen and the few the user stepped through last."""
MOST_BYTES = 256 * 2**20
"""Memory the kept inputs may hold (a grid at 1000 objects per agent is tens of MB): past it the
least recently used go, down to the latest one."""


@dataclass(frozen=True)
class Prepared:
    """Steps 1-2 and the context vectors of one input, and (in ``kept``) what local matching built
    from them that no threshold changes (``cbm.local_matching.count_candidates``)."""

    cav_boxes: np.ndarray
    """(Nc, 7) CAV boxes in the ego frame after ``init`` (step 1)."""
    ego_heading: np.ndarray
    cav_heading: np.ndarray
    signs: np.ndarray
    ego_context: Context
    cav_context: Context
    kept: dict = field(default_factory=dict, compare=False)

    def passes(self, name: str) -> int:
        """How many times the join's pass ``name`` (``"count"``: card(L_ij); ``"votes"``: the voting
        quadruples) ran on this input (``ran``)."""
        return self.kept.get("passes", {}).get(name, 0)


def recall(kept: dict | None, name: str, key: tuple):
    """What ``remember`` kept as ``name`` for exactly ``key`` (the thresholds it depends on), else None."""
    found = None if kept is None else kept.get(name)
    return found[1] if found is not None and found[0] == key else None


def kept_key(kept: dict | None, name: str) -> tuple | None:
    """The key ``remember`` last kept ``name`` for, or None."""
    found = None if kept is None else kept.get(name)
    return None if found is None else found[0]


def remember(kept: dict | None, name: str, key: tuple, value) -> None:
    """Keep ``value`` as ``name`` for ``key``, replacing the one kept before."""
    if kept is not None:
        kept[name] = (key, value)


def ran(kept: dict | None, name: str) -> None:
    """Count one run of the pass ``name`` on the input of ``kept`` (``Prepared.passes``)."""
    if kept is not None:
        passes = kept.setdefault("passes", {})
        passes[name] = passes.get(name, 0) + 1


def prepare(ego: np.ndarray, cav: np.ndarray, init: np.ndarray, heading: str) -> Prepared:
    """Steps 1-2 (eq. 5-6): the CAV boxes in the ego frame, folded headings, signs, context vectors."""
    cav_in_ego = se2.apply_boxes(init, cav)
    ego_heading, cav_heading = fold_heading(ego[:, 6]), fold_heading(cav_in_ego[:, 6])
    signs = pair_signs(ego_heading, cav_heading, heading)
    return Prepared(cav_in_ego, ego_heading, cav_heading, signs, build_context(ego[:, :2], ego_heading),
                    build_context(cav_in_ego[:, :2], cav_heading))


class Reuse:
    """The ``Prepared`` of the ``frames`` inputs used last, least recently used out, and fewer when
    they hold more than ``most_bytes``; safe to share between threads (two threads asking for a
    new input at once may both build it)."""

    def __init__(self, frames: int = FRAMES, most_bytes: int = MOST_BYTES) -> None:
        self.frames, self.most_bytes = frames, most_bytes
        self.hits = self.misses = 0
        self._entries: OrderedDict[bytes, Prepared] = OrderedDict()
        self._lock = threading.Lock()

    def __len__(self) -> int:
        return len(self._entries)

    def prepared(self, ego: np.ndarray, cav: np.ndarray, init: np.ndarray, heading: str) -> Prepared:
        """The kept ``Prepared`` of this input, or a new one (kept, dropping the oldest past ``frames``)."""
        key = _key(ego, cav, init, heading)
        with self._lock:
            found = self._entries.get(key)
            if found is not None:
                self._entries.move_to_end(key)
                self.hits += 1
                self._trim()
                return found
            self.misses += 1
        made = prepare(ego, cav, init, heading)
        with self._lock:
            self._entries[key] = made
            self._trim()
        return made

    def _trim(self) -> None:
        """Forget the least recently used inputs past ``frames`` or ``most_bytes`` (what the
        earlier calls' joins added counts), keeping the latest; called under the lock."""
        while len(self._entries) > self.frames or (len(self._entries) > 1 and self.nbytes() > self.most_bytes):
            self._entries.popitem(last=False)

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
