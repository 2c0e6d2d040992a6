"""Grid against Optuna for the parameter search on the shipped Argoverse 2 scene: the best objective
reached after N settings tried.

SIND protocol at the default scenario, every 4th frame, objective F1 (micro-averaged precision and
recall), the 36-point ``DEFAULT_SPACE``. The grid's best after N is over its first N points in grid
order; Optuna (TPE, seeds 0, 1, 2) draws from the box the grid spans. Run: python bench/bench_search.py
"""
from __future__ import annotations

import argparse
import sys
from itertools import accumulate
from pathlib import Path
from time import perf_counter

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from evaluation.run import load_source  # noqa: E402
from evaluation.scenario import ScenarioParams  # noqa: E402
from evaluation.search import DEFAULT_SPACE, grid_size, optuna_candidates, scorer  # noqa: E402

CHECKPOINTS = (5, 10, 20, 36)


def best_so_far(frames: list, objective: str, sampler_seed: int | None) -> tuple[list[float], float]:
    """The best score after each setting tried (grid order, or Optuna's draw order with
    ``sampler_seed``) and the seconds the search took; trials always from seed 0."""
    start = perf_counter()
    score = scorer(frames, ScenarioParams(), {}, objective, seed=0, workers=1, progress=None, ray=None)
    tried = (score(DEFAULT_SPACE) if sampler_seed is None
             else optuna_candidates(DEFAULT_SPACE, score, sampler_seed, grid_size()))
    return list(accumulate((c.score for c in tried), max)), perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--stride", type=int, default=4)
    parser.add_argument("--objective", default="f1")
    args = parser.parse_args()
    frames = load_source("argoverse2", "sind", frames=lambda n: range(0, n, args.stride)).inputs
    print(f"{len(frames)} frames, objective {args.objective}; best after N settings tried")
    print("| searcher | " + " | ".join(f"N={n}" for n in CHECKPOINTS) + " | time |")
    print("|---|" + "---|" * (len(CHECKPOINTS) + 1))
    print(_line("grid (grid order)", *best_so_far(frames, args.objective, None)))
    for seed in (0, 1, 2):
        print(_line(f"optuna seed {seed}", *best_so_far(frames, args.objective, seed)))


def _line(name: str, best: list[float], seconds: float) -> str:
    return f"| {name} | " + " | ".join(f"{best[n - 1]:.4f}" for n in CHECKPOINTS) + f" | {seconds:.0f} s |"


if __name__ == "__main__":
    main()
