"""Calibration accuracy under the three conditions of the accuracy issue, on our own data.

Conditions (every detection's heading turned by pi with probability 0.5):

- SIND mild: SIND protocol, eta 0.5, sigma_p 0.3 m, sigma_theta 5 deg, the CAV off by 3 m, 3 m, 5 deg;
- SIND hard: eta 0.3, sigma_p 0.6 m, sigma_theta 10 deg;
- range 50 m: the recording car (or the vehicle nearest the centroid) is the ego, the vehicle
  nearest 25 m from it the CAV, each sees 50 m around it; localization error drawn from N(0, 3 m)
  in x and y and N(0, 5 deg) in yaw; sigma_p 0.3 m, sigma_theta 5 deg.

Methods: the released code's CBM (headings folded, least-squares fit, no re-association), CBM as
published (eq. 14 fit, no re-association), CBM with this project's defaults (noise-aware fit and
guided re-association), the oracle (least squares on the true pairs), ICP, RICP, VIPS and none.
Trials come from ``evaluation`` (the trial builder the app uses too), seeds 0..S-1.
Prints, per condition and dataset, micro-averaged precision and recall, the success rate (RTE < 1 m
and RRE < 1 deg) and the median runtime per call of one worker process.

    python bench/bench_accuracy.py [--seeds 3] [--datasets argoverse2 synthetic] [--workers 2]
"""
from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import loaders  # noqa: E402
from evaluation.cli import parse_frames  # noqa: E402
from evaluation.run import frame_inputs  # noqa: E402
from evaluation.scenario import ScenarioParams  # noqa: E402
from evaluation.sweep import Sweep, run, summarise  # noqa: E402

CONDITIONS = {
    "SIND mild": ScenarioParams(protocol="sind", eta=0.5, sigma_p=0.3, sigma_theta=5.0, flip_prob=0.5),
    "SIND hard": ScenarioParams(protocol="sind", eta=0.3, sigma_p=0.6, sigma_theta=10.0, flip_prob=0.5),
    "range 50 m": ScenarioParams(protocol="range", sensor_range=50.0, localization="gaussian", loc_x=3.0,
                                 loc_y=3.0, loc_yaw=5.0, sigma_p=0.3, sigma_theta=5.0, flip_prob=0.5),
}
DATASETS = {
    "argoverse2": (("argoverse2", "all"),),
    "synthetic": tuple((f"synthetic:120:seed={s}", "0:50:2") for s in range(3)),
}
"""Dataset groups: (name, frames) of each sequence in the group."""
CBM_VARIANTS = {
    "CBM, released code + least squares": {"heading": "fold", "estimator": "least_squares", "refine": False},
    "CBM as published (eq. 14, no refinement)": {"heading": "align", "estimator": "welsch", "refine": False},
    "CBM, our defaults (noise-aware fit + re-association)": {"heading": "align", "estimator": "welsch", "refine": True},
}
OTHERS = {"oracle": "oracle (true pairs)", "icp": "ICP", "ricp": "RICP", "vips": "VIPS", "none": "none (GNSS pose)"}
GRID = {name: tuple(dict.fromkeys(v[name] for v in CBM_VARIANTS.values()))
        for name in ("heading", "estimator", "refine")}


@dataclass(frozen=True)
class Row:
    label: str
    precision: float
    recall: float
    success: float
    runtime_ms: float
    trials: int


def frames_of(name: str, frames: str, protocol: str) -> list:
    """The sweep's inputs of one sequence (the evaluation's, as the app builds its trials)."""
    seq = loaders.open(name)
    inputs, _ = frame_inputs(seq, parse_frames(frames, len(seq)), protocol, 25.0)
    return inputs


def label_of(row: dict[str, Any]) -> str | None:
    """The table label of a sweep row, or None for CBM grid points that are no named variant."""
    if row["method"] != "cbm":
        return OTHERS[row["method"]]
    return next((label for label, values in CBM_VARIANTS.items()
                 if all(row[name] == value for name, value in values.items())), None)


def measure(condition: ScenarioParams, group: str, seeds: int, workers: int) -> list[Row]:
    """Every method's aggregate over the group's sequences and ``seeds`` seeds."""
    rows: list[dict[str, Any]] = []
    for name, frames in DATASETS[group]:
        inputs = frames_of(name, frames, condition.protocol)
        for seed in range(seeds):
            sweep = Sweep(methods=("cbm", *OTHERS), grid=GRID, seed=seed, scenario=condition)
            rows.extend(run(sweep, inputs, workers=workers))
    named = [{**row, "label": label} for row in rows if (label := label_of(row)) is not None]
    runtimes: dict[str, list[float]] = {}
    for row in named:
        runtimes.setdefault(row["label"], []).append(row["runtime_s"])
    order = [*CBM_VARIANTS, *OTHERS.values()]
    stats = dict(summarise(named, ["label"]))
    return [Row(label, stats[(label,)]["precision"], stats[(label,)]["recall"], stats[(label,)]["success_rate"],
                1000 * float(np.median(runtimes[label])), int(stats[(label,)]["n_trials"])) for label in order]


def cell(value: float) -> str:
    return "-" if np.isnan(value) else f"{value:.3f}"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--datasets", nargs="+", choices=tuple(DATASETS), default=list(DATASETS))
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args(argv)
    for condition_name, condition in CONDITIONS.items():
        for group in args.datasets:
            rows = measure(condition, group, args.seeds, args.workers)
            print(f"\n### {condition_name} · {group} ({rows[0].trials} trials per method)\n")
            print("| method | precision | recall | success | median ms |")
            print("|---|---:|---:|---:|---:|")
            for row in rows:
                print(f"| {row.label} | {cell(row.precision)} | {cell(row.recall)} | {cell(row.success)} | "
                      f"{row.runtime_ms:.2f} |")


if __name__ == "__main__":
    main()
