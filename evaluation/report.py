"""Reports of an evaluation: the Table-I-shaped summary and precision against eta, in Markdown,
read from the per-trial table (``evaluation.run``)."""
from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import polars as pl

from cbm.methods import ORACLE_WORDS
from evaluation.sweep import SCENARIO_FIELDS, Sweep, summarise

from .aggregates import AP_ROWS, curve_markdown, fused_ap, success_curve
from .run import Plan

TABLE_ROWS = (
    ("Pre. (%)", "precision", 100.0),
    ("Rec. (%)", "recall", 100.0),
    ("AD (m)", "ad", 1.0),
    ("median RRE (deg)", "rre_median", 1.0),
    ("median RTE (m)", "rte_median", 1.0),
    ("success (%)", "success_rate", 100.0),
    ("success @ 2 m, 2 deg (%)", "success_rate_2", 100.0),
    ("success @ 3 m, 3 deg (%)", "success_rate_3", 100.0),
    ("abstained (%)", "abstain_rate", 100.0),
    ("success where not abstained (%)", "returned_success", 100.0),
)
RUNTIME_ROW = ("median runtime (ms)", "runtime_median_s", 1000.0)
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
    """Markdown: one row per metric, one column per method variant (the paper's Table I), plus the
    RRE/RTE of the uncalibrated ``init`` unless the method ``none`` (which reports it) is a column."""
    keyed = [{**row, "variant": v} for row, v in zip(rows, variants)]
    stats = dict(summarise(keyed, ["variant"]))
    names = [key[0] for key in stats]
    columns = [stats[(n,)] for n in names]
    if "none" not in names:
        first = [row for row in keyed if row["variant"] == names[0]]
        names.append(init_name(rows))
        columns.append({"rre_median": _median([r["init_rre"] for r in first]),
                        "rte_median": _median([r["init_rte"] for r in first])})
    lines = [f"| metric | {' | '.join(column_name(n) for n in names)} |", "|---|" + "---:|" * len(names)]
    for label, key, scale in (*TABLE_ROWS, *([RUNTIME_ROW] if timing else [])):
        lines.append(f"| {label} | {' | '.join(_cell(column.get(key, math.nan), scale) for column in columns)} |")
    ap = fused_ap(rows, variants)
    for label, threshold in AP_ROWS if ap else ():
        cells = [_cell(ap[n][threshold] if n in ap else math.nan, 100.0) for n in names]
        lines.append(f"| {label} | {' | '.join(cells)} |")
    return "\n".join(lines)


def eta_table(rows: list[dict[str, Any]], variants: list[str], sweep: Sweep) -> str:
    """Markdown: micro-averaged precision (%) per noise level and method variant (rows) and eta (columns)."""
    by = levels(sweep)
    keyed = [{**row, "variant": v} for row, v in zip(rows, variants)]
    stats = dict(summarise(keyed, [*by, "variant", "eta"]))
    etas = sweep.grid["eta"]
    lines = [f"| {' | '.join([*by, 'method'])} | {' | '.join(f'eta={fmt(e)}' for e in etas)} |",
             "|" + "---|" * (len(by) + 1) + "---:|" * len(etas)]
    for key in dict.fromkeys(k[:-1] for k in stats):
        cells = [_cell(stats[(*key, e)]["precision"], 100.0) for e in etas]
        lines.append(f"| {' | '.join(fmt(v) for v in key)} | {' | '.join(cells)} |")
    return "\n".join(lines)


def _cell(value: float, scale: float) -> str:
    return "-" if math.isnan(value) else f"{value * scale:.2f}" if scale == 1.0 else f"{value * scale:.1f}"


def _median(values: list[float]) -> float:
    finite = sorted(v for v in values if not math.isnan(v))
    if not finite:
        return math.nan
    mid = len(finite) // 2
    return finite[mid] if len(finite) % 2 else 0.5 * (finite[mid - 1] + finite[mid])


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
              table_one(rows, variants, timing=timing), "",
              "Pre./Rec.: matched pairs that are true / true pairs that were matched. AD: mean true distance "
              "between the objects of each output pair. RRE/RTE: medians over trials with an estimate. "
              "Success: RTE < 1 m and RRE < 1 deg (at 2 and 3: RTE < 2 m and RRE < 2 deg, 3 and 3). "
              "Abstained: trials where the method said it had not enough evidence (its pose is still scored); "
              "success where not abstained: over the other trials. none / GNSS (init) / init (no prior): the error "
              "before calibration; "
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
