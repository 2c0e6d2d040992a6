"""Evaluate CBM and the baselines on datasets: a tidy per-trial table, a Table-I-shaped summary and plots.

    python evaluate.py --dataset argoverse2 --frames 0:156:4 --protocol sind \\
        --grid eta=0.2,0.4,0.6,0.8 sigma_p=0,0.3 sigma_theta=0,3 --seed 0 --out results/sind

Writes into ``--out``: ``trials.parquet`` and ``trials.csv`` (one row per frame, grid point and
method: dataset, frame, method, every parameter, every metric, then ``runtime_s`` last; several
``--dataset`` names are run one after the other with the same frames and grid),
``summary.md`` (also printed), ``precision_vs_eta.png`` (when the grid varies ``eta``) and
``rre_rte.png``. Each file is written to a temporary file first and moved into place.

The same arguments give the same table byte for byte except the ``runtime_s`` column, which is
wall-clock time: with ``--no-timing`` the table (CSV and Parquet) and the summary leave it out and
are byte-identical between runs.

Trials come from the trial builder the app uses (``loaders.trials``): the dataset's ego and the
sequence's steady CAV (the vehicle most often near ``--cav-distance`` metres from the ego; in a
frame without it, the vehicle nearest that distance). ``sind`` deals the frame's objects out to the
two agents; ``range`` and ``opv2v`` need an ego and a CAV per frame (frames without are skipped).
For the paper's OPV2V setting add ``--grid localization=gaussian`` (3 m / 5 deg std-devs).
"""
from __future__ import annotations

import argparse
import math
import os
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, NoReturn, Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import polars as pl  # noqa: E402
from tqdm import tqdm  # noqa: E402

import loaders  # noqa: E402
from cbm.methods import METHODS  # noqa: E402
from cbm.scenario import ScenarioParams  # noqa: E402
from cbm.scenario import FrameInputs  # noqa: E402
from cbm.sweep import SCENARIO_FIELDS, TIMING_COLUMNS, TRIAL_COLUMNS, Sweep, grid_defaults, run, summarise  # noqa: E402
from loaders import trials  # noqa: E402
from loaders.agents import TARGET_DISTANCE  # noqa: E402

DEFAULT_METHODS = tuple(METHODS)
TABLE_ROWS = (
    ("Pre. (%)", "precision", 100.0),
    ("Rec. (%)", "recall", 100.0),
    ("AD (m)", "ad", 1.0),
    ("median RRE (deg)", "rre_median", 1.0),
    ("median RTE (m)", "rte_median", 1.0),
    ("success (%)", "success_rate", 100.0),
)
RUNTIME_ROW = ("median runtime (ms)", "runtime_median_s", 1000.0)
GNSS = "GNSS (init)"
LOG_FLOOR = 1e-3
"""RRE (deg) and RTE (m) below this are drawn at it on the log-scale plot."""
MARKERS = "osD^vP*Xh<>"


class CliError(ValueError):
    """Bad command-line input: reported in one line, exit status 2."""


class Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line on stderr and exit status 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser() -> Parser:
    """The command line of ``evaluate.py``."""
    parser = Parser(prog="evaluate.py", description=__doc__.splitlines()[0])
    parser.add_argument("--dataset", nargs="+", default=["argoverse2"],
                        help="one or more of argoverse2, synthetic[:count[:seed=S]] or a dataset path (default: argoverse2)")
    parser.add_argument("--frames", default="all",
                        help="frame indices: all, or a comma list of N and A:B[:STEP] ranges (end excluded)")
    parser.add_argument("--protocol", choices=("sind", "range", "opv2v"), default="sind")
    parser.add_argument("--methods", default=",".join(DEFAULT_METHODS),
                        help=f"comma list of {', '.join(METHODS)} (default: all)")
    parser.add_argument("--grid", nargs="+", default=[], metavar="NAME=V1,V2",
                        help="scenario or method parameters and their values, e.g. eta=0.2,0.6 sigma2=2,3")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("results"), help="output folder (default: results)")
    parser.add_argument("--workers", type=int, default=2, help="processes (default: 2)")
    parser.add_argument("--cav-distance", type=float, default=TARGET_DISTANCE,
                        help=f"preferred ego-CAV distance in metres (default: {TARGET_DISTANCE:g})")
    parser.add_argument("--no-timing", action="store_true",
                        help="leave the runtime out of the table and summary (then they are byte-identical run to run)")
    return parser


def parse_frames(text: str, n_frames: int) -> list[int]:
    """Sorted distinct frame indices from ``all`` or a comma list of ``N`` and ``A:B[:STEP]``."""
    if text.strip() == "all":
        return list(range(n_frames))
    frames: set[int] = set()
    for part in text.split(","):
        try:
            numbers = [int(p) for p in part.split(":")]
        except ValueError:
            raise CliError(f"--frames: {part!r} is not N or A:B[:STEP] with integers") from None
        if len(numbers) > 3 or min(numbers) < 0 or (len(numbers) == 3 and numbers[2] < 1):
            raise CliError(f"--frames: {part!r} is not N or A:B[:STEP] with non-negative integers and STEP >= 1")
        frames.update(numbers if len(numbers) == 1 else range(*numbers))
    outside = sorted(f for f in frames if f >= n_frames)
    if outside:
        raise CliError(f"--frames: frame {outside[0]} is out of range: the dataset has {n_frames} frames (0 to {n_frames - 1})")
    if not frames:
        raise CliError(f"--frames: {text!r} selects no frame")
    return sorted(frames)


def parse_methods(text: str) -> tuple[str, ...]:
    """The method names of a comma list, each known and given once."""
    names = tuple(name.strip() for name in text.split(","))
    unknown = [name for name in names if name not in METHODS]
    if unknown:
        raise CliError(f"--methods: unknown {unknown[0]!r}; choose from {', '.join(METHODS)}")
    if len(set(names)) != len(names):
        raise CliError(f"--methods: {text!r} names a method twice")
    return names


def parse_grid(items: Sequence[str], methods: Sequence[str]) -> dict[str, tuple[Any, ...]]:
    """``NAME=V1,V2`` items as typed values, each typed like the parameter's default (whether the
    selected ``methods`` take it is the sweep's check)."""
    defaults = grid_defaults(METHODS)
    grid: dict[str, tuple[Any, ...]] = {}
    for item in items:
        name, sep, values = item.partition("=")
        if not sep or not name or not values:
            raise CliError(f"--grid: {item!r} is not NAME=V1,V2,...")
        if name in grid:
            raise CliError(f"--grid: {name} is given twice")
        if name == "protocol":
            raise CliError("--grid: set the protocol with --protocol")
        if name not in defaults:
            known = [n for n in grid_defaults(methods) if n != "protocol"]
            raise CliError(f"--grid: unknown parameter {name!r}; known for these methods: {', '.join(known)}")
        typed = tuple(parse_value(name, value, defaults[name]) for value in values.split(","))
        if len(set(typed)) != len(typed):
            raise CliError(f"--grid: {name} repeats a value")
        grid[name] = typed
    return grid


def parse_value(name: str, text: str, default: Any) -> Any:
    """``text`` as a value of the type of ``default``."""
    text = text.strip()
    if isinstance(default, bool):
        if text.lower() not in ("true", "false"):
            raise CliError(f"--grid: {name} takes true or false, got {text!r}")
        return text.lower() == "true"
    try:
        return type(default)(text)
    except ValueError:
        raise CliError(f"--grid: {name} takes {type(default).__name__} values, got {text!r}") from None


@dataclass(frozen=True)
class Source:
    """One dataset's part of a run: what the sweep needs of each frame, and the frames skipped."""

    name: str
    inputs: list[FrameInputs]
    skipped: list[int]


def frame_inputs(seq: loaders.Sequence, frames: Sequence[int], protocol: str,
                 cav_distance: float) -> tuple[list[FrameInputs], list[int]]:
    """What the sweep needs of each frame (``loaders.trials.frame_inputs``, as the app builds its
    trials), and the frames skipped for want of an ego or a CAV."""
    if protocol == "opv2v" and seq.visibility is None:
        raise CliError(f"--protocol opv2v: {seq.name} does not say what each agent sees; use --protocol range")
    inputs, skipped = [], []
    for k in frames:
        try:
            inputs.append(trials.frame_inputs(seq[k], protocol, target_distance=cav_distance))
        except trials.NoTrial:
            skipped.append(k)
    return inputs, skipped


def variant_names(rows: Sequence[dict[str, Any]], sweep: Sweep) -> list[str]:
    """Each row's method, with the method parameters the grid varies (``cbm sigma2=2``)."""
    varied = [name for name, values in sweep.grid.items() if len(values) > 1 and name not in SCENARIO_FIELDS]
    return [" ".join([row["method"], *(f"{n}={_fmt(row[n])}" for n in varied if row[n] is not None)]) for row in rows]


def levels(sweep: Sweep) -> list[str]:
    """The scenario parameters the grid varies, ``eta`` excepted: what makes a noise level."""
    return [n for n, v in sweep.grid.items() if len(v) > 1 and n in SCENARIO_FIELDS and n != "eta"]


def _fmt(value: Any) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def table_one(rows: list[dict[str, Any]], variants: list[str], timing: bool) -> str:
    """Markdown: one row per metric, one column per method variant (the paper's Table I), plus the
    RRE/RTE of the uncalibrated ``init`` unless the method ``none`` (which reports it) is a column."""
    keyed = [{**row, "variant": v} for row, v in zip(rows, variants)]
    stats = dict(summarise(keyed, ["variant"]))
    names = [key[0] for key in stats]
    columns = [stats[(n,)] for n in names]
    if "none" not in names:
        first = [row for row in keyed if row["variant"] == names[0]]
        names.append(GNSS)
        columns.append({"rre_median": _median([r["init_rre"] for r in first]),
                        "rte_median": _median([r["init_rte"] for r in first])})
    lines = [f"| metric | {' | '.join(names)} |", "|---|" + "---:|" * len(names)]
    for label, key, scale in (*TABLE_ROWS, *([RUNTIME_ROW] if timing else [])):
        lines.append(f"| {label} | {' | '.join(_cell(column.get(key, math.nan), scale) for column in columns)} |")
    return "\n".join(lines)


def eta_table(rows: list[dict[str, Any]], variants: list[str], sweep: Sweep) -> str:
    """Markdown: micro-averaged precision (%) per noise level and method variant (rows) and eta (columns)."""
    by = levels(sweep)
    keyed = [{**row, "variant": v} for row, v in zip(rows, variants)]
    stats = dict(summarise(keyed, [*by, "variant", "eta"]))
    etas = sweep.grid["eta"]
    lines = [f"| {' | '.join([*by, 'method'])} | {' | '.join(f'eta={_fmt(e)}' for e in etas)} |",
             "|" + "---|" * (len(by) + 1) + "---:|" * len(etas)]
    for key in dict.fromkeys(k[:-1] for k in stats):
        cells = [_cell(stats[(*key, e)]["precision"], 100.0) for e in etas]
        lines.append(f"| {' | '.join(_fmt(v) for v in key)} | {' | '.join(cells)} |")
    return "\n".join(lines)


def _cell(value: float, scale: float) -> str:
    return "-" if math.isnan(value) else f"{value * scale:.2f}" if scale == 1.0 else f"{value * scale:.1f}"


def _median(values: list[float]) -> float:
    finite = sorted(v for v in values if not math.isnan(v))
    if not finite:
        return math.nan
    mid = len(finite) // 2
    return finite[mid] if len(finite) % 2 else 0.5 * (finite[mid - 1] + finite[mid])


def summary_markdown(args: argparse.Namespace, sweep: Sweep, rows: list[dict[str, Any]],
                     sources: list[Source]) -> str:
    """The whole summary page: what was run, the Table-I-shaped table and, when eta varies, precision by eta."""
    variants = variant_names(rows, sweep)
    grid = " ".join(f"{n}={','.join(_fmt(v) for v in values)}" for n, values in sweep.grid.items()) or "(none)"
    parts = [
        "# Evaluation summary", "",
        f"protocol `{args.protocol}`, seed {args.seed}, grid: `{grid}`, {len(rows) // len(set(variants))} trials x {len(set(variants))} methods.", "",
    ]
    for source in sources:
        frames = [f.index for f in source.inputs]
        skipped = f"; skipped {len(source.skipped)} without an ego or a CAV: {_ranges(source.skipped)}" if source.skipped else ""
        parts.append(f"- `{source.name}`: {len(frames)} frames ({_ranges(frames)}){skipped}")
    parts += ["", "## Association and pose (micro-averaged over all trials)", "",
              table_one(rows, variants, timing=not args.no_timing), "",
              "Pre./Rec.: matched pairs that are true / true pairs that were matched. AD: mean true distance "
              "between the objects of each output pair. RRE/RTE: medians over trials with an estimate. "
              "Success: RTE < 1 m and RRE < 1 deg. none / GNSS (init): the error before calibration; "
              "oracle: least squares on the true pairs, the limit of association-based calibration."]
    if len(sweep.grid.get("eta", ())) > 1:
        parts += ["", "## Precision (%) against the co-visibility rate eta", "", eta_table(rows, variants, sweep)]
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


def plot_precision_vs_eta(rows: list[dict[str, Any]], variants: list[str], sweep: Sweep) -> plt.Figure:
    """The paper's SIND figure: precision against eta, one panel per noise level, one line per method
    (one column per value of the last noise parameter of the grid when it has at most 5)."""
    by = levels(sweep)
    keyed = [{**row, "variant": v} for row, v in zip(rows, variants)]
    stats = summarise(keyed, [*by, "variant", "eta"])
    panels = list(dict.fromkeys(key[:-2] for key, _ in stats))
    last = len(sweep.grid[by[-1]]) if by else 1
    columns = last if last <= 5 else min(len(panels), 4)
    n_rows = math.ceil(len(panels) / columns)
    fig, axes = plt.subplots(n_rows, columns, figsize=(3.6 * columns, 3.2 * n_rows), sharey=True, squeeze=False)
    for ax, panel in zip(axes.flat, panels):
        for k, variant in enumerate(dict.fromkeys(variants)):
            points = [(key[-1], a["precision"] * 100) for key, a in stats if key[:-2] == panel and key[-2] == variant]
            ax.plot(*zip(*points), marker=MARKERS[k % len(MARKERS)], markerfacecolor="none", label=variant)
        ax.set_title(", ".join(f"{n}={_fmt(v)}" for n, v in zip(by, panel)) or "all trials", fontsize=9)
        ax.set_xlabel("co-visibility rate eta")
        ax.grid(alpha=0.3)
    for ax in axes.flat[len(panels):]:
        ax.set_visible(False)
    for ax in axes[:, 0]:
        ax.set_ylabel("precision (%)")
    axes.flat[0].legend(fontsize=8)
    fig.tight_layout()
    return fig


def plot_rre_rte(rows: list[dict[str, Any]], variants: list[str]) -> plt.Figure:
    """The paper's OPV2V figure: RRE and RTE distributions per method (trials with an estimate) and
    of the uncalibrated ``init`` (GNSS, unless the method ``none`` shows it), on a log scale."""
    names = list(dict.fromkeys(variants))
    first = [row for row, v in zip(rows, variants) if v == names[0]]
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 3.8))
    for ax, metric, unit in ((axes[0], "rre", "deg"), (axes[1], "rte", "m")):
        data = [[row[metric] for row, v in zip(rows, variants) if v == name and row["estimated"]] for name in names]
        ticks = list(names)
        if "none" not in names:
            data.append([row[f"init_{metric}"] for row in first])
            ticks.append("GNSS")
        ax.boxplot([[max(x, LOG_FLOOR) for x in d] or [math.nan] for d in data], showfliers=True)
        ax.set_xticks(range(1, len(data) + 1), ticks, rotation=30, ha="right", fontsize=8)
        ax.set_yscale("log")
        ax.set_ylabel(f"{metric.upper()} ({unit}, below {LOG_FLOOR:g} drawn at {LOG_FLOOR:g})", fontsize=8)
        ax.grid(alpha=0.3, axis="y")
    fig.tight_layout()
    return fig


def write_atomic(path: Path, write: Callable[[Path], None]) -> None:
    """Call ``write(temporary path)`` beside ``path``, then move the result onto ``path``."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        write(tmp)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def trial_table(rows: list[dict[str, Any]], sweep: Sweep, timing: bool) -> pl.DataFrame:
    """The tidy per-trial table: dataset, then the sweep's columns, the runtime last or left out."""
    columns = ["dataset", *(c for c in sweep.columns() if timing or c not in TIMING_COLUMNS)]
    data = {c: [row[c] for row in rows] for c in columns}
    return pl.DataFrame(data, strict=False).with_columns(pl.col(*TRIAL_COLUMNS).cast(pl.Utf8))


def write_outputs(args: argparse.Namespace, sweep: Sweep, rows: list[dict[str, Any]], sources: list[Source]) -> str:
    """Write the table, the summary and the plots into ``args.out``; return the summary."""
    args.out.mkdir(parents=True, exist_ok=True)
    table = trial_table(rows, sweep, timing=not args.no_timing)
    write_atomic(args.out / "trials.parquet", lambda p: table.write_parquet(p))
    write_atomic(args.out / "trials.csv", lambda p: table.write_csv(p))
    summary = summary_markdown(args, sweep, rows, sources)
    write_atomic(args.out / "summary.md", lambda p: p.write_text(summary))
    variants = variant_names(rows, sweep)
    figures = {"rre_rte.png": plot_rre_rte(rows, variants)}
    if len(sweep.grid.get("eta", ())) > 1:
        figures["precision_vs_eta.png"] = plot_precision_vs_eta(rows, variants, sweep)
    for name, fig in figures.items():
        write_atomic(args.out / name, lambda p: fig.savefig(p, format="png", dpi=120))
        plt.close(fig)
    return summary


def prepare(args: argparse.Namespace) -> tuple[Sweep, list[Source]]:
    """Check the arguments and load the frames of every dataset."""
    if args.workers < 1:
        raise CliError(f"--workers must be at least 1, got {args.workers}")
    if args.seed < 0:
        raise CliError(f"--seed must be a non-negative integer, got {args.seed}")
    if not (args.cav_distance >= 0 and math.isfinite(args.cav_distance)):
        raise CliError(f"--cav-distance must be a finite number >= 0, got {args.cav_distance}")
    if args.out.exists() and not args.out.is_dir():
        raise CliError(f"--out: {args.out} exists and is not a folder")
    if len(set(args.dataset)) != len(args.dataset):
        raise CliError("--dataset: a dataset is named twice")
    methods = parse_methods(args.methods)
    grid = parse_grid(args.grid, methods)
    try:
        sweep = Sweep(methods=methods, grid=grid, seed=args.seed, scenario=ScenarioParams(protocol=args.protocol))
    except ValueError as error:
        raise CliError(str(error)) from None
    return sweep, [load_source(name, args) for name in args.dataset]


def load_source(name: str, args: argparse.Namespace) -> Source:
    """Open dataset ``name`` and make its frame inputs for the protocol."""
    try:
        seq = loaders.open(name)
    except ValueError as error:
        raise CliError(str(error).splitlines()[0]) from None
    inputs, skipped = frame_inputs(seq, parse_frames(args.frames, len(seq)), args.protocol, args.cav_distance)
    if not inputs:
        raise CliError(f"no frame of {name} has an ego and a CAV for the {args.protocol} protocol")
    return Source(name, inputs, skipped)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the evaluation; 2 on bad input."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        sweep, sources = prepare(args)
    except CliError as error:
        parser.error(str(error))
    rows = []
    with tqdm(total=sum(sweep.trial_count(len(s.inputs)) for s in sources), unit="trial", disable=None) as bar:
        for source in sources:
            found = run(sweep, source.inputs, workers=args.workers, progress=bar.update)
            rows.extend({"dataset": source.name, **row} for row in found)
    print(write_outputs(args, sweep, rows, sources))
    print(f"wrote trials.parquet, trials.csv, summary.md and plots to {args.out}", file=sys.stderr)
    return 0

if __name__ == "__main__":
    sys.exit(main())
