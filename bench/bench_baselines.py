"""Median runtime of every method (cbm.methods) at 50 and 100 objects per agent.

Street-like scenes: vehicles in the lanes of a street grid, headings along their lanes, 60 % of each
agent's objects co-visible, detection noise 0.2 m / 2 degrees with random heading flips, and the
SIND localization error (3 m, 3 m, 5 degrees). Fixed seed. Run: python bench/bench_baselines.py
"""
from __future__ import annotations

from time import perf_counter

import numpy as np

from cbm import se2
from cbm.methods import METHODS, run

SEED = 2024
SIZES = (50, 100)
SCENES = 5
REPEATS = 5
COVISIBLE = 0.6
LANE_OFFSETS = (-5.25, -1.75, 1.75, 5.25)
STREETS = (-60.0, 0.0, 60.0)
HALF_EXTENT = 90.0
MIN_GAP = 6.0


def street_objects(rng: np.random.Generator, n: int) -> np.ndarray:
    """``n`` car boxes in the lanes of a grid of streets, at least ``MIN_GAP`` apart."""
    boxes = []
    while len(boxes) < n:
        along = rng.uniform(-HALF_EXTENT, HALF_EXTENT)
        street, lane = rng.choice(STREETS), rng.choice(LANE_OFFSETS)
        horizontal = rng.random() < 0.5
        x, y = (along, street + lane) if horizontal else (street + lane, along)
        if any(np.hypot(x - b[0], y - b[1]) < MIN_GAP for b in boxes):
            continue
        yaw = (0.0 if horizontal else np.pi / 2) + (np.pi if lane < 0 else 0.0) + rng.normal(0.0, 0.05)
        boxes.append([x, y, 0.0, rng.uniform(3.8, 5.2), rng.uniform(1.7, 2.1), rng.uniform(1.4, 1.9), yaw])
    return np.array(boxes)


def trial(rng: np.random.Generator, n_per_agent: int):
    """Ego boxes, CAV boxes, init, true transform and true pairs for one scene."""
    n_co = round(COVISIBLE * n_per_agent)
    world = street_objects(rng, n_co + 2 * (n_per_agent - n_co))
    ids = rng.permutation(len(world))
    ego_ids = rng.permutation(np.r_[ids[:n_co], ids[n_co:n_per_agent]])
    cav_ids = rng.permutation(np.r_[ids[:n_co], ids[n_per_agent:]])
    T_true = se2.make(rng.uniform(-30, 30), rng.uniform(-30, 30), rng.uniform(-np.pi, np.pi))

    def detect(boxes: np.ndarray) -> np.ndarray:
        out = boxes.copy()
        out[:, :2] += rng.normal(0.0, 0.2, (len(out), 2))
        out[:, 6] += rng.normal(0.0, np.radians(2.0), len(out)) + np.pi * (rng.random(len(out)) < 0.5)
        return out

    ego = detect(world[ego_ids])
    cav = detect(se2.apply_boxes(se2.inverse(T_true), world[cav_ids]))
    init = se2.make(3.0, 3.0, np.radians(5.0)) @ T_true
    cav_index = {obj: k for k, obj in enumerate(cav_ids)}
    truth = {(i, cav_index[obj]) for i, obj in enumerate(ego_ids) if obj in cav_index}
    return ego, cav, init, truth


def _mean(values: list[float]) -> str:
    """Mean of the defined values, or a dash when there is none (``none`` matches nothing)."""
    finite = [v for v in values if not np.isnan(v)]
    return f"{np.mean(finite):.2f}" if finite else "-"


def truth_for(name: str, truth: set[tuple[int, int]]) -> dict[str, np.ndarray]:
    """The true pairs as the methods that take them want them (the oracle)."""
    return {"true_pairs": np.array(sorted(truth)).reshape(-1, 2)} if METHODS[name].takes_truth else {}


def main() -> None:
    rng = np.random.default_rng(SEED)
    trials = {n: [trial(rng, n) for _ in range(SCENES)] for n in SIZES}
    for name in METHODS:
        run(name, *trials[SIZES[0]][0][:3], **truth_for(name, trials[SIZES[0]][0][3]))
    print(f"{'method':16} {'objects':>7} {'median ms':>10} {'precision':>10} {'recall':>7}")
    for name in METHODS:
        for n in SIZES:
            times, precisions, recalls = [], [], []
            for ego, cav, init, truth in trials[n]:
                for _ in range(REPEATS):
                    t0 = perf_counter()
                    result = run(name, ego, cav, init, **truth_for(name, truth))
                    times.append(perf_counter() - t0)
                got = {tuple(p) for p in result.pairs.tolist()}
                precisions.append(len(got & truth) / len(got) if got else np.nan)
                recalls.append(len(got & truth) / len(truth))
            print(f"{name:16} {n:7d} {1e3 * np.median(times):10.2f} {_mean(precisions):>10} {np.mean(recalls):7.2f}")


if __name__ == "__main__":
    main()
