"""The files of an evaluation: ``trials.parquet``, ``trials.csv``, ``summary.md``, ``metrics.json``,
``success_curve.csv``, ``success_curve.png``, ``rre_rte.png``, when the grid varies eta
``precision_vs_eta.png`` and, when asked for, ``summary.tex``.

A run's files are written into a staging folder beside ``--out`` (``.<name>.partial-<pid>``) and
the folder is swapped into place only once every file is complete: the older run's folder is
moved aside, the new one renamed onto ``--out``, then the old one removed. A run that fails or is
stopped removes its staging folder and leaves the older run's files untouched, so ``--out``
always holds one whole run. ``--out`` must be new, empty or a previous run's folder
(:func:`check_out`): a folder holding other files is refused rather than replaced.
"""
from __future__ import annotations

import io
import os
import shutil
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import polars as pl

from loaders.errors import unreadable

from .aggregates import curve_csv, method_metrics, metrics_json, success_curve
from .latex import summary_latex
from .plots import plot_precision_vs_eta, plot_rre_rte, plot_success_curve, plt, run_title, titled
from .report import summary_markdown, variant_names
from .run import Plan, without_timing

OUTPUT_NAMES = frozenset({"trials.parquet", "trials.csv", "summary.md", "metrics.json", "success_curve.csv",
                          "success_curve.png", "rre_rte.png", "precision_vs_eta.png", "summary.tex"})
"""Every file a run may write: a folder holding only these is a previous run's, which a new run replaces."""


class OutError(ValueError):
    """``--out`` cannot take a run's files: the message says why, in one line."""


def write_together(out: Path, files: dict[str, Callable[[Path], None]]) -> None:
    """Write every file of ``files`` (name -> ``write(temporary path)``) into ``out``: all of them, or
    none. Each is written beside its place first; only when all are complete are they moved into
    place. On a failure (a full disk) the temporaries, and ``out`` itself when this call made it,
    are removed, the files there before are untouched, and :class:`OutError` names ``out`` in one line."""
    made = not out.exists()
    temporaries = {name: out / f".{name}.{os.getpid()}.tmp" for name in files}
    try:
        out.mkdir(parents=True, exist_ok=True)
        for name, write in files.items():
            write(temporaries[name])
        for name, tmp in temporaries.items():
            os.replace(tmp, out / name)
    except OSError as error:
        for tmp in temporaries.values():
            tmp.unlink(missing_ok=True)
        if made:
            shutil.rmtree(out, ignore_errors=True)
        raise OutError(f"cannot write into {out} ({error.strerror or error}); nothing was written, "
                       "the files there before are untouched") from None


def check_out(out: Path) -> None:
    """:class:`OutError` unless ``out`` can take a run: a new folder whose nearest existing parent
    is a writable folder, or an existing folder (empty or a previous run's) whose parent is
    writable (the staging folder goes there). Writability is tried by creating a temporary file; a
    folder on the way that cannot be opened is named."""
    out = out.resolve()
    try:
        _check_out(out)
    except OSError as error:
        raise OutError(f"--out: {unreadable(error, out)}") from None


def _check_out(out: Path) -> None:
    if not out.name:
        raise OutError(f"--out: {out} cannot be replaced by a run's folder; name a folder inside it")
    if out.exists() and not out.is_dir():
        raise OutError(f"--out: {out} exists and is not a folder")
    if out.is_dir():
        foreign = sorted(p.name for p in out.iterdir() if p.name not in OUTPUT_NAMES)
        if foreign:
            raise OutError(f"--out: {out} holds {foreign[0]!r}{' and more' if len(foreign) > 1 else ''}, "
                           "which evaluate.py did not write; choose a new or empty folder or a previous run's")
    check_writable(out.parent, out)


def check_writable(folder: Path, out: Path, what: str = "--out") -> None:
    """:class:`OutError` unless the nearest existing one of ``folder`` and its parents is a folder this
    process can create a file in (``out``: what will be created there; ``what``: the option, both
    for the message)."""
    parent = next(p for p in (folder, *folder.parents) if p.exists())
    if not parent.is_dir():
        raise OutError(f"{what}: {parent} is a file, so {out} cannot be created")
    try:
        tempfile.TemporaryFile(dir=parent).close()
    except OSError as error:
        raise OutError(f"{what}: cannot write in {parent} ({error.strerror or error})") from None


@dataclass(frozen=True)
class Staged:
    """A run's complete files in a staging folder beside ``out``, waiting to replace it."""

    folder: Path
    out: Path
    summary: str

    def publish(self) -> None:
        """Swap the staging folder onto ``out``: the older run's folder is moved aside, the new one
        renamed into place, then the old one removed (on failure the older run is put back)."""
        aside = self.out.with_name(f".{self.out.name}.old-{os.getpid()}")
        had_old = self.out.exists()
        try:
            if had_old:
                os.rename(self.out, aside)
            os.rename(self.folder, self.out)
        except BaseException:
            if had_old and aside.exists() and not self.out.exists():
                os.rename(aside, self.out)
            shutil.rmtree(self.folder, ignore_errors=True)
            raise
        shutil.rmtree(aside, ignore_errors=True)


def staging_folder(out: Path) -> Path:
    """Where a run's files are written before they replace ``out``: a hidden sibling named for this process."""
    out = out.resolve()
    return out.with_name(f".{out.name}.partial-{os.getpid()}")


def stage_outputs(out: Path, plan: Plan, table: pl.DataFrame, timing: bool = True, latex: bool = False) -> Staged:
    """Write every file of the run into a staging folder beside ``out``; on any failure (or a stop)
    the staging folder is removed and ``out`` is untouched."""
    folder = staging_folder(out)
    folder.parent.mkdir(parents=True, exist_ok=True)
    try:
        folder.mkdir()
        summary = write_files(folder, plan, table, timing, latex)
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise
    return Staged(folder, out.resolve(), summary)


def write_table(table: pl.DataFrame, parquet: Path, csv: Path) -> None:
    """``table`` as Parquet and CSV files. polars builds each in memory and Python writes the bytes:
    a full disk is then ``OSError`` (ENOSPC), which the command reports in one line, instead of
    polars' ``ComputeError: parquet: File out of specification`` (issue 50, item 8)."""
    buffer = io.BytesIO()
    table.write_parquet(buffer)
    parquet.write_bytes(buffer.getbuffer())
    csv.write_text(table.write_csv())


def write_files(folder: Path, plan: Plan, table: pl.DataFrame, timing: bool = True, latex: bool = False) -> str:
    """Write the table, the summary, the metrics, the success curve and the plots into ``folder`` (with
    ``latex``, the summary as a LaTeX table too); return the summary. Without ``timing`` the table,
    the summary and the metrics leave the runtime out (then they are byte-identical run to run)."""
    written = table if timing else without_timing(table)
    write_table(written, folder / "trials.parquet", folder / "trials.csv")
    summary = summary_markdown(plan, table, timing)
    (folder / "summary.md").write_text(summary)
    rows = table.to_dicts()
    variants = variant_names(rows, plan.sweep)
    metrics = method_metrics(rows, variants, timing)
    (folder / "metrics.json").write_text(metrics_json(metrics))
    if latex:
        (folder / "summary.tex").write_text(summary_latex(metrics))
    curve = success_curve(rows, variants)
    (folder / "success_curve.csv").write_text(curve_csv(curve))
    figures = {"rre_rte.png": plot_rre_rte(rows, variants), "success_curve.png": plot_success_curve(curve)}
    if len(plan.sweep.grid.get("eta", ())) > 1:
        figures["precision_vs_eta.png"] = plot_precision_vs_eta(rows, variants, plan.sweep)
    title = run_title([(s.name, [f.index for f in s.inputs]) for s in plan.sources], plan.sweep.scenario.protocol)
    for name, fig in figures.items():
        try:
            titled(fig, title).savefig(folder / name, format="png", dpi=120)
        finally:
            plt.close(fig)
    return summary
