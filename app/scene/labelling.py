"""Labels beside what they name, never over each other nor over a thing labelled: each label in turn
takes the first free place around the thing it names (right of it, left, below, above), then farther
out a line at a time, with a short leader line back to it. A label that finds no free place within ``REACH_LINES``
waits for a click (its box's click label says the same), unless the picture must show it (an
agent's, a title, a pair that decides the result: ``kept``), which searches on.

The camera looks down with x up the screen and y to its left, so a place ``dx`` pixels right and
``dy`` pixels down of a point lies ``dy`` metres-per-pixel lower in x and ``dx`` lower in y. A label
is anchored at its top left corner (viser's ``top-left``)."""
from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field

import numpy as np

from .framing import CHAR_EM, LINE_EM
from .pairs import Labels

SLACK = 1.15
"""Room kept between two labels, as a share of a line: a camera framed a little higher than the one
they were laid out for still shows them apart."""
GAP_PX = 4.0
"""CSS pixels between a thing and the label beside it."""
REACH_LINES = 4
"""Lines a label may move away from its place beside its thing before it waits for a click."""
FAR_LINES = 60
"""Lines a label the picture must show searches for a free place."""
AGENTS = ("ego", "cav")
FIXED = ("edge_",)
"""Labels that stay where they are put, placed first (the edge markers of pairs out of view)."""
LAST = ("picked",)
Room = Mapping[str, tuple[float, float]]
"""Half the width and half the height, in metres along the screen, of the thing each label names."""
Bounds = tuple[float, float, float, float]
"""(left, top, right, bottom) of the part of the screen the labels are to stay in, in pixels of the
layout's own frame: ``-y / m`` across, ``-x / m`` down (``screen_bounds``)."""


@dataclass(frozen=True)
class Laid:
    """Labels laid out for one scale."""

    labels: Labels
    """The labels shown, each at its place."""
    leaders: np.ndarray = field(default_factory=lambda: np.zeros((0, 2, 3), np.float32))
    """(N, 2, 3) a line from each label moved off its thing's side back to the thing."""
    hidden: frozenset[str] = frozenset()
    """The labels that found no free place near their thing: shown on a click of it."""
    flush_right: frozenset[str] = frozenset()
    """The labels left of their thing: drawn flush with the right edge of their place (the text is
    often narrower than the place ``size_px`` keeps for it), so that no gap opens beside the thing."""


def rank(name: str, kept: frozenset[str]) -> int:
    """Which labels are placed first: the fixed ones (0), the agents' (1), the kept (2), the others
    (3), the click label last (4)."""
    if name.startswith(FIXED):
        return 0
    if name in LAST:
        return 4
    if name.startswith(AGENTS):
        return 1
    return 2 if name in kept else 3


def size_px(text: str, label_px: float) -> tuple[float, float]:
    """A label's width and height in CSS pixels (as ``framing.label_spot`` takes them)."""
    return CHAR_EM * label_px * len(text) + label_px / 5, LINE_EM * label_px


def places(half: tuple[float, float], size: tuple[float, float], line: float,
           lines: int) -> Iterator[tuple[int, float, float]]:
    """(ring, dx, dy): top-left corners, in pixels from the thing's centre, of the places tried for
    a label ``size`` beside a thing ``half`` pixels across and down: right, left, below and above it
    (ring 0; a point first gets its label's corner on it), then each ring a ``line`` farther: beside
    it a line lower or higher, and out on each side."""
    (rx, ry), (w, h) = half, size
    if not rx and not ry:
        yield 0, 0.0, 0.0
    right, left, middle = rx + GAP_PX, -rx - GAP_PX - w, -h / 2
    below, above = ry + GAP_PX, -ry - GAP_PX - h
    yield from ((0, right, middle), (0, left, middle), (0, -w / 2, below), (0, -w / 2, above))
    for ring in range(1, lines + 1):
        d = ring * line
        yield from ((ring, right, middle + d), (ring, right, middle - d), (ring, left, middle + d),
                    (ring, left, middle - d), (ring, -w / 2, below + d), (ring, -w / 2, above - d),
                    (ring, right + d, middle), (ring, left - d, middle))


def _clear(box: tuple[float, float, float, float], placed: list[tuple[float, float, float, float]], pad: float) -> bool:
    left, top, right, bottom = box
    return not any(left < x1 + pad and x0 - pad < right and top < y1 + pad and y0 - pad < bottom
                   for x0, y0, x1, y1 in placed)


def screen_bounds(look_at: tuple[float, ...], metres_per_px: float, width: float, height: float,
                  area: tuple[float, float, float, float]) -> Bounds:
    """The ``area`` (left, top, right, bottom CSS pixels) of a ``width`` x ``height`` canvas whose camera
    looks down at ``look_at`` showing ``metres_per_px``, in the layout's frame (``Bounds``)."""
    du, dv = -look_at[1] / metres_per_px - width / 2, -look_at[0] / metres_per_px - height / 2
    left, top, right, bottom = area
    return left + du, top + dv, right + du, bottom + dv


def _inside(box: tuple[float, float, float, float], bounds: Bounds | None) -> bool:
    return bounds is None or (bounds[0] <= box[0] and bounds[1] <= box[1] and box[2] <= bounds[2]
                              and box[3] <= bounds[3])


def lay_out(labels: Labels, metres_per_px: float, label_px: float, room: Room | None = None,
            kept: frozenset[str] = frozenset(), bounds: Bounds | None = None) -> Laid:
    """``labels`` (text and the point each names) laid out for a camera showing ``metres_per_px``
    metres of ground per CSS pixel, the text ``label_px`` high: beside the thing each names (its half
    extents ``room``; a point without), on no other label, inside ``bounds`` where a place there is
    free (a label that must show goes outside them rather than nowhere)."""
    room = room or {}
    m = max(metres_per_px, 1e-9)
    line = LINE_EM * label_px
    pad = (SLACK - 1.0) * line / 2
    placed: list[tuple[float, float, float, float]] = []
    things = [_thing(-point[1] / m, -point[0] / m, room.get(name, (0.0, 0.0)), m)
              for name, (_, point) in labels.items() if name in room]
    shown, leaders, hidden, flush = {}, [], set(), set()
    order = sorted(labels.items(), key=lambda item: (rank(item[0], kept), -item[1][1][0], item[0]))
    for name, (text, (x, y, z)) in order:
        u, v = -y / m, -x / m
        size = size_px(text, label_px)
        if name.startswith(FIXED):
            placed.append((u, v, u + size[0], v + size[1]))
            shown[name] = (text, (x, y, z))
            continue
        half = tuple(extent / m for extent in room.get(name, (0.0, 0.0)))
        must = rank(name, kept) < 3 or name in LAST
        found = _place((u, v), half, size, line, FAR_LINES if must else REACH_LINES, placed, things, pad, bounds,
                       must)
        if found is None:
            hidden.add(name)
            continue
        ring, dx, dy = found
        placed.append((u + dx, v + dy, u + dx + size[0], v + dy + size[1]))
        shown[name] = (text, (x - dy * m, y - dx * m, z))
        if dx + size[0] <= 0:
            flush.add(name)
        if ring:
            leaders.append(_leader(half, size, dx, dy, (x, y, z), m))
    segments = np.array(leaders, np.float32).reshape(-1, 2, 3)
    return Laid(shown, segments, frozenset(hidden), frozenset(flush))


def _thing(u: float, v: float, half: tuple[float, float], m: float) -> tuple[float, float, float, float]:
    """The box, in the layout's pixels, of a thing at (``u``, ``v``) ``half`` metres across and down."""
    return u - half[0] / m, v - half[1] / m, u + half[0] / m, v + half[1] / m


def _place(at: tuple[float, float], half: tuple[float, float], size: tuple[float, float], line: float, lines: int,
           placed: list[tuple[float, float, float, float]], things: list[tuple[float, float, float, float]],
           pad: float, bounds: Bounds | None, must: bool) -> tuple[int, float, float] | None:
    """The first free place (``places``: off the labels ``placed`` and the ``things`` labelled) inside
    ``bounds`` for a label of ``size`` naming the thing at ``at``; else, for a label that ``must``
    show, the first free place outside them; else None."""
    outside = None
    for ring, dx, dy in places(half, size, line, lines):
        box = (at[0] + dx, at[1] + dy, at[0] + dx + size[0], at[1] + dy + size[1])
        if not (_clear(box, placed, pad) and _clear(box, things, 0.0)):
            continue
        if _inside(box, bounds):
            return ring, dx, dy
        outside = outside or (ring, dx, dy)
    return outside if must else None


def _leader(half: tuple[float, float], size: tuple[float, float], dx: float, dy: float,
            at: tuple[float, float, float], m: float) -> list[tuple[float, float, float]]:
    """A line from the edge of a thing (``half`` pixels across and down, at ``at``) to the nearest
    point of its label's box (top left ``dx``, ``dy`` pixels from the thing's centre, ``size``)."""
    end_x = min(max(0.0, dx), dx + size[0])
    end_y = min(max(0.0, dy), dy + size[1])
    length = math.hypot(end_x, end_y) or 1.0
    reach = min(1.0, math.hypot(half[0], half[1]) / length)
    start_x, start_y = end_x * reach, end_y * reach
    x, y, z = at
    return [(x - start_y * m, y - start_x * m, z), (x - end_y * m, y - end_x * m, z)]
