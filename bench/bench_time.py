"""The cost of CBM over time and of the smoother against per-frame CBM, per frame.

Two kinds of scene: synthetic intersections of bench_match's sizes (objects per agent, about; 40
frames at 10 Hz, ``drift-clutter``'s scenario with the range widened to see every object), and the
shipped log (156 frames) under each condition over time. On each, the whole sequence is run by
``cbm.match`` frame by frame, by one ``cbm.SequenceCalibrator`` stepping through the frames in
order, and by one ``cbm.sequence.Smoother`` (its steps, then ``smoothed()``: what ``cbm-smooth``
costs), the three alternating which goes first round by round. Prints the least milliseconds per
frame of each over the rounds, the ratios to per-frame CBM (the goals: over time within 1.5x, the
smoother within 2x) and the success rate at 1 m / 1 deg of each. The kernels' first call is made
before timing.

    python bench/bench_time.py [--sizes 50 100 300] [--frames 40] [--rounds 3]
        [--conditions drift-heavy drift-clutter drift-bigloc range-50 latency]
"""
from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import loaders  # noqa: E402
from cbm import CBMParams, SequenceCalibrator, match  # noqa: E402
from cbm.methods import METHODS  # noqa: E402
from evaluation.conditions import CONDITIONS, condition  # noqa: E402
from evaluation.metrics import evaluate, is_success  # noqa: E402
from evaluation.sweep import frame_time  # noqa: E402
from evaluation.trials import sequence_inputs  # noqa: E402

HEADER = ("| scene | objects per agent | per-frame CBM ms | over time ms | smoothed ms | over time / per frame "
          "| smoothed / per frame | success per frame / over time / smoothed |")


def per_frame(frames: list) -> list:
    return [match(trial.ego_boxes, trial.cav_boxes, trial.init, CBMParams()) for _, trial in frames]


def over_time(frames: list) -> list:
    calibrator = SequenceCalibrator(CBMParams())
    return [calibrator.step(trial.ego_boxes, trial.cav_boxes, trial.init, time_s, agent=cav)
            for (time_s, cav), trial in frames]


def smoothed(frames: list) -> list:
    smoother = METHODS["cbm-smooth"].calibrator()
    for (time_s, cav), trial in frames:
        smoother.step(trial.ego_boxes, trial.cav_boxes, trial.init, time_s, agent=cav)
    return smoother.smoothed()


RUNS = {"per frame": per_frame, "over time": over_time, "smoothed": smoothed}


def measure(frames: list, rounds: int) -> dict[str, tuple[float, float]]:
    """Per run: (least ms per frame over ``rounds``, success rate at 1 m / 1 deg)."""
    first = frames[0][1]
    match(first.ego_boxes, first.cav_boxes, first.init)
    seconds: dict[str, list[float]] = {name: [] for name in RUNS}
    success: dict[str, float] = {}
    names = list(RUNS)
    for r in range(rounds):
        for name in names[r % len(names):] + names[:r % len(names)]:
            started = time.perf_counter()
            results = RUNS[name](frames)
            seconds[name].append(time.perf_counter() - started)
            success[name] = float(np.mean([is_success(evaluate(res, t)) for res, (_, t) in zip(results, frames)]))
    return {name: (1000 * min(seconds[name]) / len(frames), success[name]) for name in RUNS}


def trials(sequence: loaders.Sequence, scenario, sensor_range: float) -> list:
    """((time_s, cav), trial) of each frame of ``sequence`` that makes one, seed 0."""
    inputs, _ = sequence_inputs(sequence, range(len(sequence)), "range", sensor_range=sensor_range,
                                window_s=scenario.window_s)
    return [((frame_time(f), f.cav), f.build(scenario, 0)) for f in inputs]


def row(scene: str, frames: list, rounds: int) -> str:
    m = measure(frames, rounds)
    (alone, ok_a), (over, ok_o), (smooth, ok_s) = m["per frame"], m["over time"], m["smoothed"]
    objects = np.mean([len(trial.ego_boxes) for _, trial in frames])
    return (f"| {scene} | {objects:.0f} | {alone:.2f} | {over:.2f} | {smooth:.2f} | {over / alone:.2f} "
            f"| {smooth / alone:.2f} | {ok_a:.3f} / {ok_o:.3f} / {ok_s:.3f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[50, 100, 300])
    parser.add_argument("--frames", type=int, default=40)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--conditions", nargs="+", default=["drift-heavy", "drift-clutter", "drift-bigloc",
                                                           "range-50", "latency"])
    args = parser.parse_args()
    print(HEADER)
    print("|---|---:|---:|---:|---:|---:|---:|---|")
    for size in args.sizes:
        sequence = loaders.synthetic.generate(n_objects=int(round(2 * size / 1.5)), n_frames=args.frames, seed=size)
        scenario = dataclasses.replace(CONDITIONS["drift-clutter"], sensor_range=200.0, seed=0)
        print(row("synthetic, drift-clutter", trials(sequence, scenario, 200.0), args.rounds), flush=True)
    log = loaders.open("argoverse2")
    for name in args.conditions:
        scenario = condition(name)
        print(row(f"shipped log, {name}", trials(log, scenario, scenario.sensor_range), args.rounds), flush=True)


if __name__ == "__main__":
    main()
