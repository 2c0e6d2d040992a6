"""Calibration accuracy under the named test conditions (``evaluation.conditions``), on our own data.

Conditions: mild, hard and range-50 (the earlier accuracy issue's), heavy-noise, prior-error and
clutter (missed detections and false boxes), and drift-heavy, drift-clutter and drift-bigloc (a
localization error that drifts like GNSS); see ``evaluation.conditions``.

Methods: the released code's CBM (headings folded, least-squares fit, no re-association), CBM as
published (eq. 15 fit, no re-association), CBM with this project's defaults, CBM over time (the
frames of each sequence in time order, ``cbm.SequenceCalibrator``), and the oracle (least squares
on the true pairs, per frame); ``--others`` adds ICP, RICP, VIPS and none, and the prior-free methods:
CBM without a prior (``cbm.prior_free``), V2X-Reg++ and FreeAlign, which use no ``init``; condition
``no-prior`` is theirs (no GNSS: ``init`` is the identity). Every method runs on the same trials
(same frames, same seed, same noise draw). Every success rate is per frame, over every frame of
every sequence.
One set of CBM parameters serves every condition. Trials come from ``evaluation`` (the trial builder
the app uses too), seeds 0..S-1, so the same arguments give the same numbers.
Prints, per condition and dataset, micro-averaged precision and recall, the success rates at
1 / 2 / 3 m and degrees (RTE < t m and RRE < t deg), the share of abstentions ("not enough
evidence") and the median runtime per call of one worker process.

    python bench/bench_accuracy.py [--seeds 3] [--frames all] [--datasets argoverse2 synthetic]
        [--conditions mild clutter] [--others] [--workers 2]

``--scenes`` prints instead one table of every scene at hand and every condition over time (the
drift conditions and ``range-50``, whose errors are drawn anew each frame): per-frame CBM, the
per-frame oracle beside it, CBM over time and CBM over the whole recording (``cbm-smooth``), S@1 /
S@2 each. The scenes: the shipped log and three synthetic intersections, each also sparse (a 25 m
range: a CAV that sees 3-12 objects for long stretches).

    python bench/bench_accuracy.py --scenes [--seeds 3]
"""
from __future__ import annotations

import argparse
import dataclasses
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import loaders  # noqa: E402
from evaluation.cli import parse_frames  # noqa: E402
from evaluation.conditions import CONDITIONS, SPARSE_RANGE  # noqa: E402
from evaluation.run import frame_inputs  # noqa: E402
from evaluation.scenario import ScenarioParams  # noqa: E402
from evaluation.sweep import Sweep, run, summarise  # noqa: E402

DATASETS = {
    "argoverse2": (("argoverse2", None),),
    "synthetic": tuple((f"synthetic:120:seed={s}", "0:50:2") for s in range(3)),
}
"""Dataset groups: (name, frames) of each sequence in the group (None: the ``--frames`` option)."""
CBM_VARIANTS = {
    "CBM, released code + least squares": {"heading": "fold", "estimator": "least_squares", "refine": False},
    "CBM as published (eq. 15, no refinement)": {"heading": "align", "estimator": "welsch", "refine": False},
    "CBM, our defaults": {"heading": "align", "estimator": "welsch", "refine": True},
}
OVER_TIME = {"cbm-time": "CBM over time (our defaults)"}
SCENES = {
    "argoverse2": (("argoverse2", "all"),),
    "synthetic": tuple((f"synthetic:120:seed={s}", "0:50") for s in range(3)),
}
"""The scenes of ``--scenes``, each also sparse (``SPARSE_RANGE``)."""
SCENE_CONDITIONS = ("drift-heavy", "drift-clutter", "drift-bigloc", "range-50")
SCENE_METHODS = {"cbm": "per frame", "oracle": "oracle", "cbm-time": "over time", "cbm-smooth": "smoothed"}
REFERENCES = {"oracle": "oracle (least squares on the true pairs)"}
OTHERS = {"cbm-no-prior": "CBM without a prior (ours)", "v2xregpp": "V2X-Reg++", "freealign": "FreeAlign",
          "icp": "ICP", "ricp": "RICP", "vips": "VIPS", "none": "none (no calibration)"}
GRID = {name: tuple(dict.fromkeys(v[name] for v in CBM_VARIANTS.values()))
        for name in ("heading", "estimator", "refine")}
COLUMNS = (("precision", "precision"), ("recall", "recall"), ("S@1", "success_rate"), ("S@2", "success_rate_2"),
           ("S@3", "success_rate_3"), ("abstained", "abstain_rate"))
"""Printed columns: header and ``evaluation.metric_registry.aggregate`` key."""


@dataclass(frozen=True)
class Row:
    label: str
    stats: dict[str, float]
    runtime_ms: float
    trials: int


def frames_of(name: str, frames: str, protocol: str) -> list:
    """The sweep's inputs of one sequence (the evaluation's, as the app builds its trials)."""
    seq = loaders.open(name)
    inputs, _ = frame_inputs(seq, parse_frames(frames, len(seq)), protocol, 25.0)
    return inputs


def label_of(row: dict[str, Any], others: dict[str, str]) -> str | None:
    """The table label of a sweep row, or None for CBM grid points that are no named variant."""
    if row["method"] != "cbm":
        return {**OVER_TIME, **others}[row["method"]]
    return next((label for label, values in CBM_VARIANTS.items()
                 if all(row[name] == value for name, value in values.items())), None)


def measure(condition: ScenarioParams, group: str, seeds: int, frames: str, workers: int,
            others: dict[str, str]) -> list[Row]:
    """Every method's aggregate over the group's sequences and ``seeds`` seeds."""
    rows: list[dict[str, Any]] = []
    for name, group_frames in DATASETS[group]:
        inputs = frames_of(name, group_frames or frames, condition.protocol)
        for seed in range(seeds):
            rows.extend(run(Sweep(methods=("cbm",), grid=GRID, seed=seed, scenario=condition), inputs, workers=workers))
            rows.extend(run(Sweep(methods=tuple(others), seed=seed, scenario=condition), inputs, workers=workers))
            rows.extend(run(Sweep(methods=tuple(OVER_TIME), seed=seed, scenario=condition), inputs, workers=workers))
    named = [{**row, "label": label} for row in rows if (label := label_of(row, others)) is not None]
    runtimes: dict[str, list[float]] = {}
    for row in named:
        runtimes.setdefault(row["label"], []).append(row["runtime_s"])
    stats = dict(summarise(named, ["label"]))
    return [Row(label, stats[(label,)], 1000 * float(np.median(runtimes[label])), int(stats[(label,)]["n_trials"]))
            for label in [*CBM_VARIANTS, *OVER_TIME.values(), *others.values()]]


def cell(value: float) -> str:
    return "-" if np.isnan(value) else f"{value:.3f}"


def table(rows: list[Row]) -> str:
    """The Markdown table of one condition and dataset group."""
    lines = ["| method | " + " | ".join(h for h, _ in COLUMNS) + " | median ms |",
             "|---|" + "---:|" * (len(COLUMNS) + 1)]
    for row in rows:
        cells = " | ".join(cell(row.stats[key]) for _, key in COLUMNS)
        lines.append(f"| {row.label} | {cells} | {row.runtime_ms:.2f} |")
    return "\n".join(lines)


def scene_rates(condition: ScenarioParams, scene: str, seeds: int, workers: int) -> dict[str, tuple[float, float]]:
    """(S@1, S@2) of each of ``SCENE_METHODS`` over the scene's sequences and ``seeds`` seeds."""
    rows: list[dict[str, Any]] = []
    for name, frames in SCENES[scene]:
        seq = loaders.open(name)
        inputs, _ = frame_inputs(seq, parse_frames(frames, len(seq)), condition.protocol, 25.0,
                                 window_s=condition.window_s)
        for seed in range(seeds):
            sweep = Sweep(methods=tuple(SCENE_METHODS), seed=seed, scenario=condition)
            rows.extend(run(sweep, inputs, workers=workers))
    stats = dict(summarise(rows, ["method"]))
    return {method: (stats[(method,)]["success_rate"], stats[(method,)]["success_rate_2"]) for method in SCENE_METHODS}


def scenes_table(seeds: int, workers: int) -> str:
    """Every scene (and its sparse variant) by every over-time condition: S@1 / S@2 per method."""
    lines = ["| scene | condition | " + " | ".join(SCENE_METHODS.values()) + " |",
             "|---|---|" + "---|" * len(SCENE_METHODS)]
    for scene in SCENES:
        for sparse in (False, True):
            for name in SCENE_CONDITIONS:
                condition = CONDITIONS[name]
                if sparse:
                    condition = dataclasses.replace(condition, sensor_range=SPARSE_RANGE)
                rates = scene_rates(condition, scene, seeds, workers)
                cells = " | ".join(f"{a:.3f} / {b:.3f}" for a, b in rates.values())
                lines.append(f"| {scene}{' sparse' if sparse else ''} | {name} | {cells} |")
                print(lines[-1], flush=True)
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--frames", default="all", help="argoverse2 frames: all or A:B[:STEP] (default: all)")
    parser.add_argument("--datasets", nargs="+", choices=tuple(DATASETS), default=list(DATASETS))
    parser.add_argument("--conditions", nargs="+", choices=tuple(CONDITIONS), default=list(CONDITIONS))
    parser.add_argument("--others", action="store_true",
                        help="also CBM without a prior, V2X-Reg++, FreeAlign, ICP, RICP, VIPS and none")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--scenes", action="store_true", help="one table: every scene at hand, over time")
    args = parser.parse_args(argv)
    if args.scenes:
        print(scenes_table(args.seeds, args.workers))
        return
    others = {**REFERENCES, **(OTHERS if args.others else {})}
    for name in args.conditions:
        for group in args.datasets:
            rows = measure(CONDITIONS[name], group, args.seeds, args.frames, args.workers, others)
            print(f"\n### {name} · {group} ({rows[0].trials} trials per method)\n")
            print(table(rows), flush=True)


if __name__ == "__main__":
    main()
