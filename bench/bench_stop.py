"""How soon an abandoned computation stops (issue 40, item 1): CBM on one large frame under
``cbm.engine.threads.stoppable``, told to stop ``--after`` seconds in, and the seconds it then
ran on before ``Cancelled`` reached the caller (the issue asks for at most one).

A run is stopped once per entry of ``--after``, each a new run of the same frame (the kernels
compiled first, by ``cbm.warmup``). With ``--whole``, one run left alone first gives the steps'
times, and each stop is said to fall in the step that run was in at that time.

    python bench/bench_stop.py [--dataset synthetic:2000] [--sensor-range 300] [--false-rate 2]
                               [--after 1 5 20 45 60 90] [--whole]
"""
from __future__ import annotations

import argparse
import contextlib
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import loaders  # noqa: E402
from cbm import CBMParams, match  # noqa: E402
from cbm.engine.threads import Cancelled, stoppable  # noqa: E402
from cbm.warmup import VARIANTS, warm_up  # noqa: E402
from evaluation.scenario import ScenarioParams  # noqa: E402
from evaluation.trials import build_trial  # noqa: E402

STEPS = ("context", "local_matching", "consensus_selection", "estimate", "reassociate")


def stopped_after(trial, after: float) -> float:
    """Seconds from the moment ``after`` seconds into CBM's run when it was told to stop, to the
    moment ``Cancelled`` reached this caller (negative: it finished before the stop)."""
    told = time.perf_counter() + after
    with contextlib.suppress(Cancelled), stoppable(lambda: time.perf_counter() >= told):
        match(trial.ego_boxes, trial.cav_boxes, trial.init, CBMParams())
    return time.perf_counter() - told


def step_at(timings: dict[str, float], seconds: float) -> str:
    """The step an unstopped run with these ``timings`` was in ``seconds`` after it started."""
    elapsed = 0.0
    for step in STEPS:
        elapsed += timings.get(step, 0.0)
        if seconds < elapsed:
            return step
    return "done"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dataset", default="synthetic:2000")
    parser.add_argument("--sensor-range", type=float, default=300.0)
    parser.add_argument("--false-rate", type=float, default=2.0)
    parser.add_argument("--after", type=float, nargs="+", default=[1, 5, 20, 45, 60, 90])
    parser.add_argument("--whole", action="store_true", help="also time one run left alone (its steps)")
    args = parser.parse_args(argv)
    scenario = ScenarioParams(protocol="range", sensor_range=args.sensor_range, false_rate=args.false_rate)
    trial = build_trial(loaders.open(args.dataset)[0], scenario, 0)
    print(f"{args.dataset}, range {args.sensor_range:g} m, false_rate {args.false_rate:g}: "
          f"{len(trial.ego_boxes)} ego and {len(trial.cav_boxes)} CAV boxes")
    warm_up(VARIANTS[:1])
    timings = match(trial.ego_boxes, trial.cav_boxes, trial.init, CBMParams()).timings if args.whole else {}
    if timings:
        print("unstopped: " + ", ".join(f"{step} {timings.get(step, 0.0):.1f} s" for step in STEPS)
              + f", total {timings['total']:.1f} s")
    print("| stopped after (s) | step | ran on past the stop (s) |\n|---:|---|---:|")
    for after in args.after:
        late = stopped_after(trial, after)
        where = step_at(timings, after) if timings else "-"
        print(f"| {after:g} | {where} | {late:.2f} |" if late >= 0 else f"| {after:g} | {where} | finished first |",
              flush=True)


if __name__ == "__main__":
    main()
