"""Parameter search: the CBM thresholds that work best on a sequence.

Two searchers rank settings by an objective of the micro-averaged metrics over the frames:

- ``grid`` (default): every point of a grid over sigma1, sigma2, sigma3 (and the distance limit),
  run through ``evaluation.sweep`` -- each frame's trial made once and every grid point matched on it. Its
  points are independent (they run on the sweep's process pool or on Ray), its result does not
  depend on a sampler's history, and every point it tried is in the table for the user to read.
- ``optuna``: Optuna's TPE sampler (seeded) draws ``n_trials`` settings from the box the grid spans
  (each parameter between its smallest and largest grid value), each scored on every frame; each
  draw depends on the scores before it, so the trials run one after another.
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


SEARCHERS = ("grid", "optuna")
def _score(value: float) -> float:
    return value if math.isfinite(value) else -math.inf


def search(frames: Sequence[FrameInputs], scenario: ScenarioParams, *,
           space: Mapping[str, Sequence[float]] | None = None, objective: str = "success",
           base: Mapping[str, Any] | None = None, seed: int = 0, workers: int = 1,
           progress: Callable[[int], None] | None = None, searcher: str = "grid", n_trials: int | None = None,
           ray: str | None = None) -> list[Candidate]:
    """Every setting the ``searcher`` tried on ``frames``, scored, best first.

    ``base`` holds the CBM parameters that stay fixed (e.g. the heading mode). Ties are broken by
    the mean RTE, then the median consensus margin (``rank_key``), else keep the order tried, so
    the ranking is reproducible; the same ``seed`` gives the same trials as the app (and
    the same Optuna draws). ``n_trials`` is Optuna's budget (default: the grid's size).
    """
    space = dict(DEFAULT_SPACE if space is None else space)
    unknown = [name for name in space if name not in SEARCHABLE]
    if unknown or not space:
        raise ValueError(f"space must name some of {SEARCHABLE}, got {sorted(space)}")
    if objective not in OBJECTIVES:
        raise ValueError(f"objective must be one of {sorted(OBJECTIVES)}, got {objective!r}")
    if searcher not in SEARCHERS:
        raise ValueError(f"searcher must be one of {', '.join(SEARCHERS)}, got {searcher!r}")
    fixed = {name: [value] for name, value in (base or {}).items() if name not in space}
    score = scorer(frames, scenario, fixed, objective, seed=seed, workers=workers, progress=progress, ray=ray)
    if searcher == "optuna":
        tried = optuna_candidates(space, score, seed, grid_size(space) if n_trials is None else n_trials)
    else:
        tried = score(space)
    return sorted(tried, key=rank_key)


def rank_key(candidate: Candidate) -> tuple[float, float, float]:
    """Best first: the higher score; on a tie the lower mean RTE, then the higher median consensus
    margin (an undefined one ranks last)."""
    summary = candidate.summary
    rte, margin = summary.get("rte_mean", math.nan), summary.get("margin_median", math.nan)
    return -candidate.score, math.inf if math.isnan(rte) else rte, math.inf if math.isnan(margin) else -margin


def all_tie(candidates: Sequence[Candidate]) -> bool:
    """Whether every candidate (two or more) has the same score: the tie-breaks alone rank them."""
    return len(candidates) > 1 and len({c.score for c in candidates}) == 1


def scorer(frames: Sequence[FrameInputs], scenario: ScenarioParams, fixed: Mapping[str, Sequence[Any]],
           objective: str, *, seed: int = 0, workers: int = 1, progress: Callable[[int], None] | None = None,
           ray: str | None = None) -> Callable[[Mapping[str, Sequence[float]]], list[Candidate]]:
    """A function scoring every point of a grid on ``frames`` (one sweep, ``fixed`` parameters
    added), in grid order."""
    def score(space: Mapping[str, Sequence[float]]) -> list[Candidate]:
        sweep = Sweep(methods=("cbm",), grid={**fixed, **space}, seed=seed, scenario=scenario)
        rows = run(sweep, frames, workers=workers, progress=progress, ray=ray)
        names = list(space)
        return [Candidate(dict(zip(names, key)), _score(OBJECTIVES[objective](summary)), summary)
                for key, summary in summarise(rows, by=names)]
    return score


def optuna_candidates(space: Mapping[str, Sequence[float]],
                      score: Callable[[Mapping[str, Sequence[float]]], list[Candidate]],
                      seed: int, n_trials: int) -> list[Candidate]:
    """``n_trials`` settings drawn by a seeded TPE sampler in the box ``space`` spans, in the order tried."""
    try:
        import optuna
    except ImportError:
        raise ValueError("the optuna searcher needs Optuna, which is not installed: pip install .[optuna]") from None
    if n_trials < 1:
        raise ValueError(f"n_trials must be at least 1, got {n_trials}")
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    tried: list[Candidate] = []

    def objective(trial: Any) -> float:
        point = {name: _suggest(trial, name, values) for name, values in space.items()}
        tried.extend(score({name: (value,) for name, value in point.items()}))
        return tried[-1].score if math.isfinite(tried[-1].score) else -1.0

    study = optuna.create_study(direction="maximize", sampler=optuna.samplers.TPESampler(seed=seed))
    study.optimize(objective, n_trials=n_trials)
    return tried


def _suggest(trial: Any, name: str, values: Sequence[float]) -> float:
    low, high = float(min(values)), float(max(values))
    return low if low == high else trial.suggest_float(name, low, high)


def grid_size(space: Mapping[str, Sequence[float]] | None = None) -> int:
    """How many settings a grid search tries."""
    return math.prod(len(values) for values in (DEFAULT_SPACE if space is None else space).values())
