"""Reports of an evaluation: the Table-I-shaped summary and precision against eta, in Markdown,
read from the per-trial table (``evaluation.run``)."""
from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import polars as pl

from cbm.methods import ORACLE_WORDS
from evaluation.metric_registry import RUN_METRICS, SHARE, RunMetric, aggregate, run_metrics
from evaluation.metrics import TrialMetrics
from evaluation.sweep import SCENARIO_FIELDS, Sweep, summarise

from .aggregates import AP_ROWS, curve_markdown, fused_ap, success_curve
from .run import Plan

ORACLE_COLUMN = f"oracle ({ORACLE_WORDS})"
"""The oracle's column header and its name in the notes."""
FUSION_NOTE = ("AP@0.5 / AP@0.7: late fusion (`evaluation.fusion`): the CAV's boxes placed by the method's pose, "
               "merged with the ego's, duplicates removed by NMS at rotated BEV IoU 0.15; fused boxes against the true "
               "boxes of every object either agent sees, matched greedily by score at BEV IoU 0.5 / 0.7, all "
               "detections of the run sorted by score, VOC 2010 all-point interpolation (OpenCOOD's `eval_utils`). "
               "Scores of simulated detections: the seeded score model of `evaluation.fusion`. The oracle's boxes are "
               "placed by the true pose.")


def init_name(rows: list[dict[str, Any]]) -> str:
    """The column of the pose before calibration: GNSS's error, unless a trial had no prior
    (``localization="none"``: the identity or a guess)."""
    return "GNSS (init)" if all(row.get("localization") != "none" for row in rows) else "init (no prior)"


def variant_names(rows: Sequence[dict[str, Any]], sweep: Sweep) -> list[str]:
    """Each row's method, with the method parameters the grid varies (``cbm sigma2=2``)."""
    varied = [name for name, values in sweep.grid.items() if len(values) > 1 and name not in SCENARIO_FIELDS]
    return [" ".join([row["method"], *(f"{n}={fmt(row[n])}" for n in varied if row[n] is not None)]) for row in rows]


def levels(sweep: Sweep) -> list[str]:
    """The scenario parameters the grid varies, ``eta`` excepted: what makes a noise level."""
    return [n for n, v in sweep.grid.items() if len(v) > 1 and n in SCENARIO_FIELDS and n != "eta"]


def fmt(value: Any) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def column_name(variant: str) -> str:
    """A method variant's column header: the oracle named for what it is."""
    method, _, rest = variant.partition(" ")
    return " ".join([ORACLE_COLUMN, rest]).strip() if method == "oracle" else variant


def table_one(rows: list[dict[str, Any]], variants: list[str], timing: bool) -> str:
    """Markdown: one row per run metric (``evaluation.metric_registry``), one column per method
    variant (the paper's Table I), plus the uncalibrated ``init`` unless the method ``none`` (which
    reports it) is a column."""
    keyed = [{**row, "variant": v} for row, v in zip(rows, variants)]
    stats = dict(summarise(keyed, ["variant"]))
    names = [key[0] for key in stats]
    columns = [stats[(n,)] for n in names]
    if "none" not in names:
        names.append(init_name(rows))
        columns.append(aggregate([init_record(row) for row in keyed if row["variant"] == names[0]]))
    lines = [f"| metric | {' | '.join(column_name(n) for n in names)} |", "|---|" + "---:|" * len(names)]
    for metric in run_metrics(timing):
        lines.append(f"| {metric.heading} | {' | '.join(metric.unit.shown(c[metric.key]) for c in columns)} |")
    ap = fused_ap(rows, variants)
    for label, threshold in AP_ROWS if ap else ():
        cells = [SHARE.shown(ap[n][threshold] if n in ap else math.nan) for n in names]
        lines.append(f"| {label} | {' | '.join(cells)} |")
    return "\n".join(lines)


def init_record(row: dict[str, Any]) -> TrialMetrics:
    """What the pose before calibration scores on a row's trial, as the method ``none`` would:
    nothing matched, its RRE and RTE."""
    return TrialMetrics(n_ego=row["n_ego"], n_cav=row["n_cav"], n_true=row["n_true"], n_matched=0, n_correct=0,
                        precision=math.nan, recall=0.0 if row["n_true"] else math.nan, ad=math.nan,
                        rre=row["init_rre"], rte=row["init_rte"], runtime_s=math.nan, margin=math.nan, estimated=True)


def definitions(metrics: Sequence[RunMetric]) -> list[str]:
    """One line per formula of ``metrics`` (a formula several metrics share, once)."""
    return [f"- {formula}" for formula in dict.fromkeys(metric.formula for metric in metrics)]


def eta_table(rows: list[dict[str, Any]], variants: list[str], sweep: Sweep) -> str:
    """Markdown: micro-averaged precision (%) per noise level and method variant (rows) and eta (columns)."""
    by = levels(sweep)
    keyed = [{**row, "variant": v} for row, v in zip(rows, variants)]
    stats = dict(summarise(keyed, [*by, "variant", "eta"]))
    etas = sweep.grid["eta"]
    lines = [f"| {' | '.join([*by, 'method'])} | {' | '.join(f'eta={fmt(e)}' for e in etas)} |",
             "|" + "---|" * (len(by) + 1) + "---:|" * len(etas)]
    for key in dict.fromkeys(k[:-1] for k in stats):
        cells = [RUN_METRICS["precision"].unit.shown(stats[(*key, e)]["precision"]) for e in etas]
        lines.append(f"| {' | '.join(fmt(v) for v in key)} | {' | '.join(cells)} |")
    return "\n".join(lines)


def summary_markdown(plan: Plan, table: pl.DataFrame, timing: bool = True) -> str:
    """The whole summary page: what was run, the Table-I-shaped table and, when eta varies,
    precision by eta (``timing``: with the median runtime row)."""
    sweep, rows = plan.sweep, table.to_dicts()
    variants = variant_names(rows, sweep)
    grid = " ".join(f"{n}={','.join(fmt(v) for v in values)}" for n, values in sweep.grid.items()) or "(none)"
    parts = [
        "# Evaluation summary", "",
        f"protocol `{sweep.scenario.protocol}`, seed {sweep.seed}, grid: `{grid}`, "
        f"{len(rows) // len(set(variants))} trials x {len(set(variants))} methods.", "",
    ]
    for source in plan.sources:
        frames = [f.index for f in source.inputs]
        skipped = (f"; skipped {len(source.skipped)} without an ego or a CAV: {_ranges(source.skipped)}"
                   if source.skipped else "")
        short = (f"; {len(source.short)} with fewer CAVs than asked (too few vehicles): {_ranges(source.short)}"
                 if source.short else "")
        parts.append(f"- `{source.name}`: {len(set(frames))} frames ({_ranges(sorted(set(frames)))}){skipped}{short}")
    parts += ["", "## Association and pose (micro-averaged over all trials)", "",
              table_one(rows, variants, timing=timing), "", *definitions(run_metrics(timing)), "",
              "none / GNSS (init) / init (no prior): the error before calibration, as the method none reports it; "
              f"{ORACLE_COLUMN}: the objects both agents see, paired by their true ids and fitted by plain least "
              "squares; a reference, not a bound: a robust fit or a pose graph over more agents can come closer to "
              "the true pose."]
    if sweep.fusion:
        parts += ["", FUSION_NOTE]
    if len(sweep.grid.get("eta", ())) > 1:
        parts += ["", "## Precision (%) against the co-visibility rate eta", "", eta_table(rows, variants, sweep)]
    parts += ["", "## Success rate (%) against the error threshold (all trials)", "",
              curve_markdown(success_curve(rows, variants))]
    return "\n".join(parts) + "\n"


def _ranges(frames: list[int]) -> str:
    """``0-4, 7, 9-10`` for a sorted list of integers."""
    runs: list[list[int]] = []
    for f in frames:
        if runs and f == runs[-1][-1] + 1:
            runs[-1].append(f)
        else:
            runs.append([f])
    return ", ".join(str(r[0]) if len(r) == 1 else f"{r[0]}-{r[-1]}" for r in runs)
