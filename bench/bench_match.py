"""Benchmark of cbm.match under the SIND protocol on synthetic intersections.

Per layout (``street``: the synthetic intersection; ``dense``: a car park, every 5 m, any heading)
and size (objects per agent) prints the median and worst time of ``match`` against the target, the
median time of the floor (``floor.py``: a bare kernel counting the same quadruples on the same
trials, in the same run) and the ratio of the two medians,
the peak resident memory of a fresh process running it (and how much of it ``match`` added), and
micro-averaged precision and recall. Each size runs in its own process so that the memory peak
belongs to that size alone. The kernels' first call (compiling them, or loading them from numba's
on-disk cache) is timed apart and never counted in the match times.

    python bench/bench_match.py [--sizes 100 300 1000] [--trials 7] [--layouts street dense]
"""
from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests"), str(ROOT / "bench")]

ETA = 0.5
TARGET_MS = {"street": {100: 4.0, 300: 20.0, 1000: 450.0}, "dense": {100: 4.0, 300: 30.0, 1000: 600.0}}
"""Issue 26's targets on a 2-core machine."""
SCENARIO = dict(protocol="sind", eta=ETA, sigma_p=0.3, sigma_theta=3.0, flip_prob=0.5)


def trials_for(size: int, count: int, layout: str):
    """``count`` trials of about ``size`` objects per agent on one scene of ``layout``."""
    import loaders
    from evaluation.scenario import ScenarioParams, make_trial
    from support.scenes import dense_scene

    n_world = int(round(2 * size / (1 + ETA)))
    if layout == "dense":
        boxes, ids = dense_scene(n_world, np.random.default_rng(size)), np.arange(n_world)
    else:
        frame = loaders.synthetic.generate(n_objects=n_world, n_frames=1, seed=size)[0]
        boxes, ids = frame.boxes(), frame.track_ids
    return [make_trial(boxes, ids, ScenarioParams(**SCENARIO, seed=seed)) for seed in range(count)]


def measure(size: int, count: int, heading: str, layout: str) -> dict:
    from floor import floor_seconds

    from cbm import CBMParams, match
    from evaluation.metric_registry import aggregate
    from evaluation.metrics import evaluate

    params = CBMParams(heading=heading)
    trials = trials_for(size, count, layout)
    started = time.perf_counter()
    match(trials[0].ego_boxes[:60], trials[0].cav_boxes[:60], trials[0].init, params)
    floor_seconds(trials[0].ego_boxes[:60], trials[0].cav_boxes[:60], trials[0].init, params)
    first_call = time.perf_counter() - started
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    seconds, floors, metrics = [], [], []
    for trial in trials:
        started = time.perf_counter()
        result = match(trial.ego_boxes, trial.cav_boxes, trial.init, params)
        seconds.append(time.perf_counter() - started)
        floors.append(floor_seconds(trial.ego_boxes, trial.cav_boxes, trial.init, params)[0])
        metrics.append(evaluate(result, trial))
    summary = aggregate(metrics)
    return dict(size=size, n_ego=float(np.mean([len(t.ego_boxes) for t in trials])), first_call_ms=1000 * first_call,
                median_ms=1000 * float(np.median(seconds)), worst_ms=1000 * float(np.max(seconds)),
                floor_ms=1000 * float(np.median(floors)),
                peak_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, base_mb=before / 1024,
                precision=summary["precision"], recall=summary["recall"], success=summary["success_rate"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 300, 1000])
    parser.add_argument("--trials", type=int, default=7)
    parser.add_argument("--heading", choices=["fold", "align"], default="align")
    parser.add_argument("--layouts", choices=["street", "dense"], nargs="+", default=["street", "dense"])
    parser.add_argument("--one", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--layout", choices=["street", "dense"], default="street", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one is not None:
        print(json.dumps(measure(args.one, args.trials if args.one < 500 else max(3, args.trials // 2), args.heading,
                                 args.layout)))
        return
    print(f"cbm.match, SIND protocol (eta={ETA}, sigma_p=0.3 m, sigma_theta=3 deg, flip 0.5, 3 m/3 m/5 deg), "
          f"heading={args.heading}, {args.trials} trials per size (3 from 500 objects), one process per size")
    print("| layout | objects per agent | median ms | worst ms | floor ms | median / floor | target ms "
          "| peak memory MB (process, + match) | first call ms (compile or cache load) | precision | recall "
          "| success |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for layout in args.layouts:
        for size in args.sizes:
            print(row(layout, size, args), flush=True)


def row(layout: str, size: int, args: argparse.Namespace) -> str:
    """One size of one layout, measured in a process of its own, as a table row."""
    out = subprocess.run([sys.executable, __file__, "--one", str(size), "--trials", str(args.trials),
                          "--heading", args.heading, "--layout", layout], capture_output=True, text=True, check=True)
    r = json.loads(out.stdout.strip().splitlines()[-1])
    target = f"{TARGET_MS[layout][size]:g}" if size in TARGET_MS[layout] else "-"
    return (f"| {layout} | {r['n_ego']:.0f} | {r['median_ms']:.1f} | {r['worst_ms']:.1f} | {r['floor_ms']:.1f} "
            f"| {r['median_ms'] / r['floor_ms']:.1f} | {target} | {r['peak_mb']:.0f} "
            f"(+{r['peak_mb'] - r['base_mb']:.0f}) | {r['first_call_ms']:.0f} | {r['precision']:.3f} "
            f"| {r['recall']:.3f} | {r['success']:.2f} |")


if __name__ == "__main__":
    main()
