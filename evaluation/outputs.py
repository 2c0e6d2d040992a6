"""The files of an evaluation, each written to a temporary file beside it and moved into place:
``trials.parquet``, ``trials.csv``, ``summary.md``, ``metrics.json``, ``success_curve.csv``,
``success_curve.png``, ``rre_rte.png``, when the grid varies eta ``precision_vs_eta.png`` and,
when asked for, ``summary.tex``."""
from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import polars as pl

from .aggregates import curve_csv, method_metrics, metrics_json, success_curve
from .latex import summary_latex
from .plots import plot_precision_vs_eta, plot_rre_rte, plot_success_curve, plt
from .report import summary_markdown, variant_names
from .run import Plan, without_timing


def write_atomic(path: Path, write: Callable[[Path], None]) -> None:
    """Call ``write(temporary path)`` beside ``path``, then move the result onto ``path``."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        write(tmp)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_outputs(out: Path, plan: Plan, table: pl.DataFrame, timing: bool = True, latex: bool = False) -> str:
    """Write the table, the summary, the metrics, the success curve and the plots into ``out`` (with
    ``latex``, the summary as a LaTeX table too); return the summary. Without ``timing`` the table,
    the summary and the metrics leave the runtime out (then they are byte-identical run to run)."""
    out.mkdir(parents=True, exist_ok=True)
    written = table if timing else without_timing(table)
    write_atomic(out / "trials.parquet", lambda p: written.write_parquet(p))
    write_atomic(out / "trials.csv", lambda p: written.write_csv(p))
    summary = summary_markdown(plan, table, timing)
    write_atomic(out / "summary.md", lambda p: p.write_text(summary))
    rows = table.to_dicts()
    variants = variant_names(rows, plan.sweep)
    metrics = method_metrics(rows, variants, timing)
    write_atomic(out / "metrics.json", lambda p: p.write_text(metrics_json(metrics)))
    if latex:
        write_atomic(out / "summary.tex", lambda p: p.write_text(summary_latex(metrics)))
    curve = success_curve(rows, variants)
    write_atomic(out / "success_curve.csv", lambda p: p.write_text(curve_csv(curve)))
    figures = {"rre_rte.png": plot_rre_rte(rows, variants), "success_curve.png": plot_success_curve(curve)}
    if len(plan.sweep.grid.get("eta", ())) > 1:
        figures["precision_vs_eta.png"] = plot_precision_vs_eta(rows, variants, plan.sweep)
    for name, fig in figures.items():
        write_atomic(out / name, lambda p, fig=fig: fig.savefig(p, format="png", dpi=120))
        plt.close(fig)
    return summary
