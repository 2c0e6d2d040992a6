"""Two runs side by side: per-method differences (run B minus run A) of every metric in their
``metrics.json``, and of their success curves (``success_curve.csv``) when both have one.

    python evaluate.py compare results/before results/after     # also: cbm-evaluate compare A B

Prints the differences as Markdown and writes ``compare.md`` and ``compare.png`` (a bar chart of
the differences of the headline run metrics, ``evaluation.metric_registry``) into ``--out``
(default: ``RUN_B/compare_vs_<name of RUN_A>/``).
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import polars as pl

from loaders.errors import unreadable

from . import run_files
from .metric_registry import run_metrics
from .outputs import OutError, check_writable, write_together
from .plots import plot_differences, plt

SETTINGS = ("success_rte_max_m", "success_rre_max_deg")
"""Keys that say how a metric was computed, not how well a method did: not compared."""


class CompareError(ValueError):
    """A run folder that cannot be compared: reported in one line, exit status 2."""


def load_metrics(run: Path) -> dict[str, dict[str, Any]]:
    """The ``metrics.json`` of run folder ``run``; ``CompareError`` naming what is missing or wrong."""
    if not run.exists():
        raise CompareError(f"{run}: no such folder")
    if not run.is_dir():
        raise CompareError(f"{run}: not a folder")
    path = run / "metrics.json"
    try:
        found = path.exists()
    except OSError as error:
        raise CompareError(f"{run}: cannot open the folder ({error.strerror or error})") from None
    if not found:
        raise CompareError(f"{run} has no metrics.json: not an evaluation run, or one from before metrics.json")
    try:
        return run_files.load_metrics(path)
    except run_files.RunFileError as error:
        raise CompareError(str(error)) from None


def load_curve(run: Path) -> pl.DataFrame | None:
    """The run's ``success_curve.csv``, or None when it has none; ``CompareError`` when it is not one."""
    try:
        return run_files.load_curve(run / "success_curve.csv")
    except run_files.RunFileError as error:
        raise CompareError(str(error)) from None


def _number(value: Any) -> float:
    return math.nan if value is None or isinstance(value, bool) else float(value)


def differences(a: Mapping[str, Mapping[str, Any]], b: Mapping[str, Mapping[str, Any]]) -> dict[str, dict[str, float]]:
    """For each method in both runs, B minus A of each numeric key both have (NaN where either is
    null); settings such as the success thresholds are left out."""
    found: dict[str, dict[str, float]] = {}
    for name in (n for n in b if n in a):
        keys = [k for k in b[name] if k in a[name] and k not in SETTINGS
                and isinstance(b[name][k], (int, float, type(None))) and not isinstance(b[name][k], bool)]
        found[name] = {k: _number(b[name][k]) - _number(a[name][k]) for k in keys}
    return found


def _signed(value: float) -> str:
    return "-" if math.isnan(value) else "0" if value == 0 else f"{value:+.4g}"


def differences_markdown(found: Mapping[str, Mapping[str, float]]) -> str:
    """Markdown: one row per method, one column per key, cells B minus A."""
    keys = list(dict.fromkeys(k for values in found.values() for k in values))
    lines = [f"| method | {' | '.join(keys)} |", "|---|" + "---:|" * len(keys)]
    lines += [f"| {name} | {' | '.join(_signed(values.get(k, math.nan)) for k in keys)} |"
              for name, values in found.items()]
    return "\n".join(lines)


def curve_differences_markdown(a: pl.DataFrame, b: pl.DataFrame) -> str | None:
    """Markdown: success-rate difference (B minus A, percentage points) per threshold and common
    method, when both curves have the same thresholds; None otherwise."""
    names = [c for c in b.columns[2:] if c in a.columns[2:]]
    if not names or a["rte_max_m"].to_list() != b["rte_max_m"].to_list():
        return None
    lines = [f"| threshold t | {' | '.join(names)} |", "|---:|" + "---:|" * len(names)]
    for k, t in enumerate(b["rte_max_m"].to_list()):
        cells = [_signed(100.0 * (_number(b[n][k]) - _number(a[n][k]))) for n in names]
        lines.append(f"| {t:g} | {' | '.join(cells)} |")
    return "\n".join(lines)


def mismatches(run_a: Path, run_b: Path) -> list[str]:
    """Why the two runs may not be comparable: one line per setting (dataset, protocol) whose values
    differ between their ``trials.parquet``; empty when they agree or either run lacks the table."""
    a, b = run_files.provenance(run_a), run_files.provenance(run_b)
    if a is None or b is None:
        return []
    return [f"the runs differ in {key}: {', '.join(a[key]) or '-'} in {run_a}, {', '.join(b[key]) or '-'} in {run_b}"
            for key in ("dataset", "protocol") if a[key] != b[key]]


def compare_report(run_a: Path, run_b: Path) -> tuple[str, dict[str, dict[str, float]]]:
    """The printed comparison of two run folders, and the differences per method."""
    a, b = load_metrics(run_a), load_metrics(run_b)
    curve_a, curve_b = load_curve(run_a), load_curve(run_b)
    found = differences(a, b)
    parts = [f"# {run_b} minus {run_a}", ""]
    parts += [f"**Warning:** {line}; the differences mix settings, not only methods."
              for line in mismatches(run_a, run_b)]
    parts += ["", "## Metrics (B - A)", ""] if parts[-1] else ["## Metrics (B - A)", ""]
    parts.append(differences_markdown(found) if found else "No method is in both runs.")
    only_a, only_b = [n for n in a if n not in b], [n for n in b if n not in a]
    if only_a or only_b:
        parts.append("")
    parts += [f"Only in {run_a}: {', '.join(only_a)}"] if only_a else []
    parts += [f"Only in {run_b}: {', '.join(only_b)}"] if only_b else []
    table = curve_differences_markdown(curve_a, curve_b) if curve_a is not None and curve_b is not None else None
    if table:
        parts += ["", "## Success rate (percentage points, B - A) at RTE < t m and RRE < t deg", "", table]
    return "\n".join(parts) + "\n", found


def check_compare_out(out: Path, given: bool) -> None:
    """``CompareError`` unless ``out`` is a folder, or can be made one, in a writable place; ``given``:
    whether the user named it (``--out``) or it is the default inside run B."""
    what = "--out" if given else f"the default output folder (give --out FOLDER elsewhere): {out}"
    try:
        _check_compare_out(out.absolute(), what)
    except OSError as error:
        raise CompareError(f"{what}: {unreadable(error, out)}") from None


def _check_compare_out(out: Path, what: str) -> None:
    if out.exists() and not out.is_dir():
        raise CompareError(f"{what}: {out} exists and is not a folder")
    try:
        check_writable(out, out, what)
    except OutError as error:
        raise CompareError(str(error)) from None


def compare(run_a: Path, run_b: Path, out: Path | None = None) -> str:
    """Compare two run folders: write ``compare.md`` and ``compare.png`` into ``out`` (default
    ``RUN_B/compare_vs_<name of RUN_A>``) and return the report. ``CompareError`` for a run that
    cannot be read or an ``out`` that cannot take the files."""
    report, found = compare_report(run_a, run_b)
    given = out is not None
    out = out if out is not None else run_b / f"compare_vs_{run_a.resolve().name}"
    check_compare_out(out, given)
    headline = [metric.saved_as for metric in run_metrics() if metric.headline]
    lower_better = {metric.saved_as for metric in run_metrics() if metric.better == "lower"}
    fig = plot_differences(found, headline, lower_better, f"{run_b.name} minus {run_a.name}")
    try:
        write_together(out, {"compare.md": lambda p: p.write_text(report),
                             "compare.png": lambda p: fig.savefig(p, format="png", dpi=120)})
    except OutError as error:
        raise CompareError(str(error)) from None
    finally:
        plt.close(fig)
    return report
