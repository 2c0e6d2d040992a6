"""Parameter search: the CBM thresholds that work best on a sequence.

A grid over sigma1, sigma2, sigma3 (and the distance limit) run through ``cbm.sweep`` -- each frame's
trial is made once and every grid point matched on it -- then ranked by an objective of the
micro-averaged metrics. A grid, rather than a sequential optimiser, because its points are
independent (both cores work at once through the sweep's process pool), its result does not depend
on a sampler's history, and every point it tried is in the table for the user to read.
"""
from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from .scenario import FrameInputs, ScenarioParams
from .sweep import Sweep, run, summarise

SEARCHABLE = ("sigma1", "sigma2", "sigma3", "distance_limit")
DEFAULT_SPACE: dict[str, tuple[float, ...]] = {
    "sigma1": (5.0, 10.0, 15.0),
    "sigma2": (1.5, 2.0, 3.0, 4.0),
    "sigma3": (0.5, 1.0, 2.0),
}
"""Grid searched when none is given: 36 settings around the released code's defaults."""


def f1(summary: Mapping[str, float]) -> float:
    """F1 = 2 P R / (P + R) of the micro-averaged precision P and recall R (0 when undefined)."""
    p, r = summary["precision"], summary["recall"]
    return 0.0 if not (p + r > 0) else 2 * p * r / (p + r)


OBJECTIVES: dict[str, Callable[[Mapping[str, float]], float]] = {
    "success": lambda s: s["success_rate"],
    "f1": f1,
    "precision": lambda s: s["precision"],
    "recall": lambda s: s["recall"],
}
"""Objectives to maximise: ``success`` is the share of frames with RTE < 1 m and RRE < 1 degree."""


@dataclass(frozen=True)
class Candidate:
    """One grid point and what it scored."""

    params: dict[str, float]
    score: float
    summary: dict[str, float]


def _score(value: float) -> float:
    return value if math.isfinite(value) else -math.inf


def search(frames: Sequence[FrameInputs], scenario: ScenarioParams, *,
           space: Mapping[str, Sequence[float]] | None = None, objective: str = "success",
           base: Mapping[str, Any] | None = None, seed: int = 0, workers: int = 1,
           progress: Callable[[int], None] | None = None) -> list[Candidate]:
    """Every grid point of ``space`` scored on ``frames``, best first.

    ``base`` holds the CBM parameters that stay fixed (e.g. the heading mode). Ties keep the grid's
    order, so the ranking is reproducible; the same ``seed`` gives the same trials as the app.
    """
    space = dict(DEFAULT_SPACE if space is None else space)
    unknown = [name for name in space if name not in SEARCHABLE]
    if unknown or not space:
        raise ValueError(f"space must name some of {SEARCHABLE}, got {sorted(space)}")
    if objective not in OBJECTIVES:
        raise ValueError(f"objective must be one of {sorted(OBJECTIVES)}, got {objective!r}")
    fixed = {name: [value] for name, value in (base or {}).items() if name not in space}
    sweep = Sweep(methods=("cbm",), grid={**fixed, **space}, seed=seed, scenario=scenario)
    rows = run(sweep, frames, workers=workers, progress=progress)
    names = list(space)
    ranked = [Candidate(dict(zip(names, key)), _score(OBJECTIVES[objective](summary)), summary)
              for key, summary in summarise(rows, by=names)]
    return sorted(ranked, key=lambda c: -c.score)


def grid_size(space: Mapping[str, Sequence[float]] | None = None) -> int:
    """How many settings a search tries."""
    return math.prod(len(values) for values in (DEFAULT_SPACE if space is None else space).values())
