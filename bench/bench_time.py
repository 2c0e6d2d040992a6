"""The cost of CBM over time against per-frame CBM, per frame, on bench_match-sized scenes.

Per size (objects per agent, about) a synthetic intersection of 40 frames at 10 Hz under a drifting
localization error (``drift-clutter``'s scenario, the range protocol widened to see every object);
each frame is run by ``cbm.match`` and by one ``cbm.SequenceCalibrator`` stepping through the frames
in order, alternating which goes first. Prints the median milliseconds per frame of both, their
ratio, and the success rate at 1 m / 1 deg of both. The kernels' first call is made before timing.

    python bench/bench_time.py [--sizes 50 100 300] [--frames 40]
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
from evaluation.conditions import CONDITIONS  # noqa: E402
from evaluation.metrics import evaluate, is_success  # noqa: E402
from evaluation.trials import sequence_inputs  # noqa: E402


def measure(size: int, n_frames: int) -> dict[str, float]:
    sequence = loaders.synthetic.generate(n_objects=int(round(2 * size / 1.5)), n_frames=n_frames, seed=size)
    scenario = dataclasses.replace(CONDITIONS["drift-clutter"], sensor_range=200.0, seed=0)
    inputs, _ = sequence_inputs(sequence, range(len(sequence)), "range", sensor_range=scenario.sensor_range)
    trials = [(frame, frame.build(scenario, 0)) for frame in inputs]
    match(trials[0][1].ego_boxes, trials[0][1].cav_boxes, trials[0][1].init)
    calibrator = SequenceCalibrator(CBMParams())
    alone, over, ok_alone, ok_over, objects = [], [], [], [], []
    for k, (frame, trial) in enumerate(trials):
        args, time_s = (trial.ego_boxes, trial.cav_boxes, trial.init), float(sequence.timestamps[frame.index])
        runs = [("alone", lambda a=args: match(*a)),
                ("over", lambda a=args, t=time_s: calibrator.step(*a, t, agent="cav"))]
        for name, call in runs if k % 2 == 0 else runs[::-1]:
            started = time.perf_counter()
            result = call()
            (alone if name == "alone" else over).append(time.perf_counter() - started)
            (ok_alone if name == "alone" else ok_over).append(is_success(evaluate(result, trial)))
        objects.append(len(trial.ego_boxes))
    return dict(objects=float(np.mean(objects)), alone=1000 * float(np.median(alone)),
                over=1000 * float(np.median(over)), ok_alone=float(np.mean(ok_alone)), ok_over=float(np.mean(ok_over)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[50, 100, 300])
    parser.add_argument("--frames", type=int, default=40)
    args = parser.parse_args()
    print("| objects per agent | per-frame CBM ms | CBM over time ms | ratio | success per frame | success over time |")
    print("|---:|---:|---:|---:|---:|---:|")
    for size in args.sizes:
        r = measure(size, args.frames)
        print(f"| {r['objects']:.0f} | {r['alone']:.2f} | {r['over']:.2f} | {r['over'] / r['alone']:.2f} "
              f"| {r['ok_alone']:.3f} | {r['ok_over']:.3f} |", flush=True)


if __name__ == "__main__":
    main()
