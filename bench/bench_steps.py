"""Per-step times of ``cbm.match`` (``MatchResult.timings``), two checkouts side by side.

On a machine others load too, only times taken in the same session mean anything: each round runs
every scene once in each checkout (in a process of its own, alternating which goes first), and the
medians over the rounds are printed per step with their ratio (other / this checkout).

    python bench/bench_steps.py --against ../base [--scenes street:100 street:300 dense:300] [--rounds 5]

Without ``--against`` it prints this checkout's medians only. The trials are ``bench_match.py``'s.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
STEPS = ("context", "local_matching", "voting_sets", "consensus_selection", "estimate", "reassociate", "total")


def one_run(scene: str, trials: int) -> dict[str, list[float]]:
    """Per step, the milliseconds of each trial of ``scene`` (``layout:size``) after a first call."""
    sys.path[:0] = [str(ROOT), str(ROOT / "tests"), str(ROOT / "bench")]
    from bench_match import trials_for

    from cbm import CBMParams, match

    layout, size = scene.split(":")
    found = trials_for(int(size), trials, layout)
    match(found[0].ego_boxes[:60], found[0].cav_boxes[:60], found[0].init, CBMParams())
    times: dict[str, list[float]] = {step: [] for step in STEPS}
    for trial in found:
        timings = match(trial.ego_boxes, trial.cav_boxes, trial.init, CBMParams()).timings
        for step in STEPS:
            times[step].append(1000 * timings.get(step, 0.0))
    return times


def run_in(checkout: Path, scene: str, trials: int) -> dict[str, list[float]]:
    """``one_run`` in a fresh process importing ``checkout``'s sources."""
    code = (f"import sys, json; sys.path.insert(0, {str(ROOT / 'bench')!r}); import bench_steps; "
            f"bench_steps.ROOT = bench_steps.Path({str(checkout)!r}); "
            f"print(json.dumps(bench_steps.one_run({scene!r}, {trials})))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=checkout)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", type=Path, help="the other checkout (the baseline)")
    parser.add_argument("--scenes", nargs="+", default=["street:100", "street:300", "dense:300"])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--trials", type=int, default=7)
    args = parser.parse_args()
    checkouts = {"this": ROOT} if args.against is None else {"base": args.against.resolve(), "this": ROOT}
    for scene in args.scenes:
        runs: dict[str, dict[str, list[float]]] = {name: {step: [] for step in STEPS} for name in checkouts}
        for round_ in range(args.rounds):
            names = list(checkouts) if round_ % 2 == 0 else list(reversed(checkouts))
            for name in names:
                for step, values in run_in(checkouts[name], scene, args.trials).items():
                    runs[name][step].append(float(np.median(values)))
        print(f"{scene}, median ms over {args.rounds} rounds of {args.trials} trials")
        print("| step | " + " | ".join(checkouts) + (" | base / this |" if len(checkouts) == 2 else " |"))
        for step in STEPS:
            medians = {name: float(np.median(runs[name][step])) for name in checkouts}
            ratio = f" | {medians['base'] / max(medians['this'], 1e-9):.2f}" if len(checkouts) == 2 else ""
            print(f"| {step} | " + " | ".join(f"{m:.1f}" for m in medians.values()) + ratio + " |", flush=True)


if __name__ == "__main__":
    main()
