"""Per-method aggregates of an evaluation in machine-readable form: ``metrics.json`` (each method's
run metrics, ``evaluation.metric_registry``, under its name) and the success rate as a curve over
error thresholds.

    success_curve(rows, variants)  # [(0.5, {"cbm": 0.2, ...}), (1.0, {...}), ..., (5.0, {...})]
"""
from __future__ import annotations

import io
import json
import math
from collections.abc import Mapping, Sequence
from typing import Any

import polars as pl

from evaluation.ap import IOU_THRESHOLDS, pooled_ap
from evaluation.fusion import decoded
from evaluation.metric_registry import HEADLINE_LEVEL, run_metrics
from evaluation.sweep import summarise

SUCCESS_RTE_M = SUCCESS_RRE_DEG = HEADLINE_LEVEL
"""The thresholds of ``success_rate`` (``evaluation.metrics.is_success``): RTE < 1 m and RRE < 1 deg."""
THRESHOLDS = tuple(0.5 * k for k in range(1, 11))
"""The success curve's thresholds t, 0.5 to 5 in 0.5 steps: RTE < t m and RRE < t deg."""


def method_metrics(rows: Sequence[Mapping[str, Any]], variants: Sequence[str],
                   timing: bool = True) -> dict[str, dict[str, Any]]:
    """Each method variant's run metrics over all its trials (``evaluation.metric_registry``), under
    their ``metrics.json`` keys, with its trial counts and the success thresholds; NaN where nothing
    was measured. ``timing``: with the metrics that measure time. With late fusion (the rows have
    ``fused`` detections), each method's ``ap@0.5`` and ``ap@0.7`` too (``fused_ap``)."""
    keyed = [{**row, "variant": v} for row, v in zip(rows, variants)]
    found: dict[str, dict[str, Any]] = {}
    for (name,), stats in summarise(keyed, ["variant"]):
        found[name] = {metric.saved_as: float(stats[metric.key]) for metric in run_metrics(timing)}
        found[name].update(n_trials=int(stats["n_trials"]), n_estimated=int(stats["n_estimated"]),
                           success_rte_max_m=SUCCESS_RTE_M, success_rre_max_deg=SUCCESS_RRE_DEG)
    for name, ap in fused_ap(rows, variants).items():
        found[name].update({f"ap@{t:g}": value for t, value in ap.items()})
    return found


def fused_ap(rows: Sequence[Mapping[str, Any]], variants: Sequence[str]) -> dict[str, dict[float, float]]:
    """Late-fusion AP of each method variant at ``evaluation.ap.IOU_THRESHOLDS``: its fused detections
    of every trial pooled and sorted by score over the whole run (OpenCOOD's global sort), not a
    mean of per-trial APs; empty when the rows have no fusion columns."""
    groups: dict[str, list[tuple[list[tuple[float, bool, bool]], int]]] = {}
    for row, variant in zip(rows, variants):
        if row.get("fused") is None:
            return {}
        groups.setdefault(variant, []).append(decoded(row))
    return {name: pooled_ap(frames) for name, frames in groups.items()}


AP_ROWS = tuple((f"AP@{t:g} (%)", t) for t in IOU_THRESHOLDS)
"""Summary rows of the late-fusion AP (BEV IoU thresholds)."""


def metrics_json(metrics: Mapping[str, Mapping[str, Any]]) -> str:
    """``metrics`` as JSON text: numbers as JSON numbers, NaN as ``null``."""
    clean = {name: {k: None if isinstance(v, float) and math.isnan(v) else v for k, v in values.items()}
             for name, values in metrics.items()}
    return json.dumps(clean, indent=2, allow_nan=False) + "\n"


def success_rate_at(rows: Sequence[Mapping[str, Any]], threshold: float) -> float:
    """Share of ``rows`` whose pose was estimated with RTE < threshold (m) and RRE < threshold (deg);
    NaN for no rows."""
    if not rows:
        return math.nan
    passed = sum(bool(r["estimated"]) and r["rte"] < threshold and r["rre"] < threshold for r in rows)
    return passed / len(rows)


def success_curve(rows: Sequence[Mapping[str, Any]], variants: Sequence[str],
                  thresholds: Sequence[float] = THRESHOLDS) -> list[tuple[float, dict[str, float]]]:
    """The success rate of each method variant at each threshold, in order of first appearance."""
    groups: dict[str, list[Mapping[str, Any]]] = {}
    for row, variant in zip(rows, variants):
        groups.setdefault(variant, []).append(row)
    return [(t, {name: success_rate_at(group, t) for name, group in groups.items()}) for t in thresholds]


def curve_csv(curve: Sequence[tuple[float, Mapping[str, float]]]) -> str:
    """The curve as CSV: ``rte_max_m``, ``rre_max_deg``, then one success-rate column per method."""
    names = list(curve[0][1]) if curve else []
    columns = {"rte_max_m": [t for t, _ in curve], "rre_max_deg": [t for t, _ in curve],
               **{name: [rates[name] for _, rates in curve] for name in names}}
    frame = pl.DataFrame(columns, schema=dict.fromkeys(columns, pl.Float64))
    buffer = io.StringIO()
    frame.write_csv(buffer)
    return buffer.getvalue()


def curve_markdown(curve: Sequence[tuple[float, Mapping[str, float]]]) -> str:
    """Markdown: success rate (%) per threshold (rows) and method (columns)."""
    names = list(curve[0][1]) if curve else []
    lines = [f"| RTE < (m) | RRE < (deg) | {' | '.join(names)} |", "|---:|---:|" + "---:|" * len(names)]
    for t, rates in curve:
        cells = ["-" if math.isnan(rates[n]) else f"{rates[n] * 100:.1f}" for n in names]
        lines.append(f"| {t:g} | {t:g} | {' | '.join(cells)} |")
    return "\n".join(lines)
