"""Evaluate CBM and the baselines on datasets: a tidy per-trial table, a Table-I-shaped summary and plots.

    python evaluate.py --dataset argoverse2 --frames 0:156:4 --protocol sind \\
        --grid eta=0.2,0.4,0.6,0.8 sigma_p=0,0.3 sigma_theta=0,3 --seed 0 --out results/sind

Writes into ``--out``: ``trials.parquet`` and ``trials.csv`` (one row per frame, grid point and
method: dataset, frame, method, every parameter, every metric, then ``runtime_s`` last; several
``--dataset`` names are run one after the other with the same frames and grid),
``summary.md`` (also printed), ``metrics.json`` (each method's aggregate metrics under its name),
``success_curve.csv`` and ``success_curve.png`` (success rate at RTE < t m and RRE < t deg for t
from 0.5 to 5), ``precision_vs_eta.png`` (when the grid varies ``eta``), ``rre_rte.png`` and, with
``--latex``, ``summary.tex``. ``--out`` is checked before the run (new, empty or a previous run's
folder, in a writable place); the files are written into a staging folder beside it that replaces it
only once complete, so a failed or stopped run (SIGINT, SIGTERM: exit 128 + the signal) leaves the
older run's files whole (``evaluation.outputs``, ``evaluation.stop``).

    python evaluate.py compare RUN_A RUN_B [--out FOLDER]

prints the per-method differences (B - A) of two runs' metrics and plots them (``evaluation.compare``).

The same arguments give the same table byte for byte except the ``runtime_s`` column, which is
wall-clock time: with ``--no-timing`` the table (CSV and Parquet) and the summary leave it out and
are byte-identical between runs.

Defaults are the app's: the shipped ``default`` preset's scenario (the range protocol, 0.2 m and
2 degree detection noise, the CAV off by 3 m, 3 m and 5 degrees) and method parameters.
``--preset`` starts from another preset instead, a shipped one by name or a file the app saved or
exported (``evaluation.presets``); ``--condition NAME`` takes the scenario of a named test condition
(``evaluation.conditions``: mild, hard, range-50, heavy-noise, prior-error, clutter, drift-heavy,
drift-clutter, drift-bigloc, drift-sparse, no-prior, occluded, latency) in place of the preset's;
``--protocol``, ``--seed`` and ``--grid`` change it further.

Trials come from the trial builder the app uses (``evaluation.trials``): the dataset's ego and the
sequence's steady CAV (the vehicle most often near ``--cav-distance`` metres from the ego; in a
frame without it, the vehicle nearest that distance). ``sind`` deals the frame's objects out to the
two agents; ``range`` and ``opv2v`` need an ego and a CAV per frame (frames without are skipped).
For the paper's OPV2V setting add ``--grid localization=gaussian`` (3 m / 5 deg std-devs).
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import os
import signal
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NoReturn

from tqdm import tqdm

import loaders
from cbm.methods import METHODS
from evaluation.agents import TARGET_DISTANCE
from evaluation.executors import ExecutorError, TaskError, check_reachable
from evaluation.fusion import FUSIONS
from evaluation.presets import PresetError, PresetParams, default_preset, find_preset, shipped_names
from evaluation.sweep import grid_defaults

from . import calibration_check
from .bounds import bounded_workers, cost_warnings, grid_too_large
from .compare import CompareError, compare, mismatches
from .conditions import CONDITIONS
from .outputs import OutError, check_out, stage_outputs
from .run import DEFAULT_METHODS, Plan, plan, run_plan
from .stop import Stopped, StopSignals, Watchdog, kill_descendants


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
                        help="one or more of argoverse2, synthetic[:count[:seed=S]] or a dataset path "
                             "(default: argoverse2)")
    parser.add_argument("--frames", default="all",
                        help="frame indices: all, or a comma list of N and A:B[:STEP] ranges (end excluded)")
    parser.add_argument("--preset", default=None, metavar="NAME_OR_FILE",
                        help="start from a preset: a shipped one by name (" + ", ".join(shipped_names()) + ") or a "
                             "TOML file the app saved or exported (default: default, the app's defaults)")
    parser.add_argument("--condition", choices=tuple(CONDITIONS), default=None,
                        help="a named test condition's scenario in place of the preset's (evaluation.conditions: "
                             + ", ".join(CONDITIONS) + ")")
    parser.add_argument("--protocol", choices=("sind", "range", "opv2v"), default=None,
                        help="scenario protocol (default: the preset's; range for the default preset)")
    parser.add_argument("--methods", default=",".join(DEFAULT_METHODS),
                        help=f"comma list of {', '.join(METHODS)} (default: all)")
    parser.add_argument("--grid", nargs="+", default=[], metavar="NAME=V1,V2",
                        help="scenario or method parameters and their values, e.g. eta=0.2,0.6 sigma2=2,3; "
                             "tracking.<field> for CBM over time's tracking, e.g. tracking.gate=2.5,5")
    parser.add_argument("--seed", type=int, default=None, help="seed of every random draw (default: the preset's, 0)")
    parser.add_argument("--out", type=Path, default=Path("results"), help="output folder (default: results)")
    parser.add_argument("--workers", type=int, default=2, help="processes (default: 2)")
    parser.add_argument("--ray", default=None, metavar="{local,auto,ADDRESS}",
                        help="run the sweep on Ray: local (a local instance with --workers CPUs), auto (the cluster "
                             "`ray start` joined) or HOST:PORT (default: the local process pool; pip install .[ray])")
    parser.add_argument("--agents", type=int, default=2,
                        help="the ego and N-1 CAVs: one trial row per CAV and frame, each CAV calibrated to the "
                             "ego (default: 2; 3+ enables the cbm-graph method)")
    parser.add_argument("--cav-distance", type=float, default=TARGET_DISTANCE,
                        help=f"preferred ego-CAV distance in metres (default: {TARGET_DISTANCE:g})")
    parser.add_argument("--detections", default=None, metavar="STAGE1_BOXES_JSON",
                        help="CoAlign / HEAL stage1_boxes.json: a detector's boxes replace the simulated detections "
                             "(one dataset only)")
    parser.add_argument("--score-threshold", type=float, default=None, metavar="S",
                        help="drop the --detections boxes scored below S, 0 to 1: the scenario's min_score "
                             "(default: the preset's, 0: keep all; no effect on a file without pred_score_np_list)")
    parser.add_argument("--fusion", choices=FUSIONS, default=None,
                        help="late fusion after calibration (nms: OpenCOOD's, rotated BEV IoU 0.15) and its AP@0.5 / "
                             "AP@0.7 in the summary and metrics.json")
    parser.add_argument("--no-timing", action="store_true",
                        help="leave the runtime out of the table and summary (then they are byte-identical run to run)")
    parser.add_argument("--check-calibration", nargs="?", const="1,1", default=None, metavar="M,DEG",
                        help="check each --dataset's own transform against its own labels instead of evaluating: "
                             "writes calibration_check.csv / .png and the frames off by more than M metres or DEG "
                             "degrees (default 1,1) to --out (evaluation.calibration_check)")
    parser.add_argument("--latex", action="store_true",
                        help="also write the summary as a LaTeX table (summary.tex, booktabs)")
    parser.epilog = "Compare two runs: %(prog)s compare RUN_A RUN_B [--out FOLDER] (see %(prog)s compare --help)."
    return parser


def build_compare_parser(prog: str) -> Parser:
    """The command line of ``compare``: two run folders and where the comparison goes."""
    parser = Parser(prog=f"{prog} compare",
                    description="Print and plot the per-method differences (B - A) of two evaluation runs.")
    parser.add_argument("run_a", type=Path, metavar="RUN_A", help="the baseline run folder (with metrics.json)")
    parser.add_argument("run_b", type=Path, metavar="RUN_B", help="the run compared with it")
    parser.add_argument("--out", type=Path, default=None,
                        help="folder for compare.md and compare.png (default: RUN_B/compare_vs_<RUN_A name>)")
    return parser


def parse_frames(text: str, n_frames: int) -> list[int]:
    """Sorted distinct frame indices from ``all`` or a comma list of ``N`` and ``A:B[:STEP]``. Each
    range is checked against ``n_frames`` before it is expanded, so memory stays within the dataset's length."""
    if text.strip() == "all":
        return list(range(n_frames))
    ranges = [_frame_range(part) for part in text.split(",")]
    outside = [_first_at_or_after(r, n_frames) for r in ranges if r and r[-1] >= n_frames]
    if outside:
        raise CliError(f"--frames: frame {min(outside)} is out of range: "
                       f"the dataset has {n_frames} frames (0 to {n_frames - 1})")
    frames = sorted(set().union(*ranges))
    if not frames:
        raise CliError(f"--frames: {text!r} selects no frame")
    return frames


def _frame_range(part: str) -> range:
    """``N`` or ``A:B[:STEP]`` as a range (not expanded)."""
    try:
        numbers = [int(p) for p in part.split(":")]
    except ValueError:
        raise CliError(f"--frames: {part!r} is not N or A:B[:STEP] with integers") from None
    if len(numbers) > 3 or min(numbers) < 0 or (len(numbers) == 3 and numbers[2] < 1):
        raise CliError(f"--frames: {part!r} is not N or A:B[:STEP] with non-negative integers and STEP >= 1")
    return range(numbers[0], numbers[0] + 1) if len(numbers) == 1 else range(*numbers)


def _first_at_or_after(frames: range, n: int) -> int:
    """The smallest index of ``frames`` (increasing, its last one >= ``n``) that is at least ``n``."""
    steps = max(0, -(-(n - frames.start) // frames.step))
    return frames.start + steps * frames.step


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


def score_threshold(args: argparse.Namespace) -> float:
    """``--score-threshold``, checked: from 0 to 1, and only with ``--detections`` (it drops a detector's boxes)."""
    value = args.score_threshold
    if not 0.0 <= value <= 1.0:
        raise CliError(f"--score-threshold must be a number from 0 to 1, got {value}")
    if args.detections is None:
        raise CliError("--score-threshold drops a detector's boxes by score: give --detections too")
    return value


def read_preset(name_or_file: str | None) -> PresetParams:
    """The preset ``--preset`` names (None: the default one)."""
    try:
        return default_preset() if name_or_file is None else find_preset(name_or_file)
    except PresetError as error:
        raise CliError(f"--preset: {error}") from None


def prepare(args: argparse.Namespace) -> Plan:
    """Check the arguments and load the frames of every dataset; ``CliError`` names what is wrong."""
    if args.workers < 1:
        raise CliError(f"--workers must be at least 1, got {args.workers}")
    preset = read_preset(args.preset)
    seed = preset.scenario.seed if args.seed is None else args.seed
    if seed < 0:
        raise CliError(f"--seed must be a non-negative integer, got {seed}")
    if not (args.cav_distance >= 0 and math.isfinite(args.cav_distance)):
        raise CliError(f"--cav-distance must be a finite number >= 0, got {args.cav_distance}")
    try:
        check_out(args.out)
    except OutError as error:
        raise CliError(str(error)) from None
    if len(set(args.dataset)) != len(args.dataset):
        raise CliError("--dataset: a dataset is named twice")
    if args.ray not in (None, "local", "auto"):
        try:
            check_reachable(args.ray)
        except ExecutorError as error:
            raise CliError(str(error)) from None
    if args.detections is not None and len(args.dataset) != 1:
        raise CliError("--detections: give exactly one --dataset (the detections belong to one dataset)")
    scenario = preset.scenario if args.condition is None else CONDITIONS[args.condition]
    if args.score_threshold is not None:
        scenario = dataclasses.replace(scenario, min_score=score_threshold(args))
    methods = parse_methods(args.methods)
    grid = parse_grid(args.grid, methods)
    too_large = grid_too_large(grid)
    if too_large:
        raise CliError(too_large)
    try:
        return plan(args.dataset, methods=methods, grid=grid, seed=seed, protocol=args.protocol,
                    frames=lambda n: parse_frames(args.frames, n), cav_distance=args.cav_distance,
                    detections=args.detections, fusion=args.fusion, agents=args.agents,
                    scenario=scenario, params=preset.params, tracking=preset.tracking)
    except ValueError as error:
        raise CliError(str(error)) from None


def main_compare(argv: Sequence[str], prog: str) -> int:
    """Compare two runs (``evaluation.compare``); 2 on bad input."""
    parser = build_compare_parser(prog)
    args = parser.parse_args(argv)
    try:
        print(compare(args.run_a, args.run_b, args.out), end="")
    except CompareError as error:
        parser.error(str(error))
    for line in mismatches(args.run_a, args.run_b):
        print(f"{parser.prog}: warning: {line}", file=sys.stderr)
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Run the evaluation, or with a first argument ``compare`` compare two runs; 2 on bad input,
    128 + the signal's number when SIGINT or SIGTERM stops it (then nothing is written)."""
    parser = build_parser()
    command = argv is None
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] == ["compare"]:
        return main_compare(argv[1:], parser.prog)
    args = parser.parse_args(argv)
    if args.check_calibration is not None:
        return check_calibration(parser, args)
    with StopSignals() as signals:
        watchdog = Watchdog(lambda name: f"{parser.prog}: stopped by {name}; nothing written",
                            held=lambda: signals.holding) if command else None
        try:
            code = evaluate(parser, args, signals)
        except Stopped as stop:
            if watchdog:
                watchdog.disarm()
            print(f"{parser.prog}: stopped by {stop.name}; nothing written", file=sys.stderr)
            code = 128 + stop.signum
            if command:
                exit_now(code)
        if watchdog:
            watchdog.disarm()
    return code


def check_calibration(parser: Parser, args: argparse.Namespace) -> int:
    """``--check-calibration``: the dataset-calibration check of every ``--dataset`` (2 on bad input)."""
    try:
        thresholds = calibration_check.parse_thresholds(args.check_calibration)
        calibration_check.check_out_folder(args.out)
        rows = []
        for name in args.dataset:
            sequence = loaders.open(name)
            rows += calibration_check.check_sequence(sequence, parse_frames(args.frames, len(sequence)), thresholds)
    except ValueError as error:
        parser.error(str(error))
    try:
        flagged = calibration_check.write_check(rows, thresholds, args.out)
    except OutError as error:
        parser.error(f"--out: {error}")
    print(flagged, end="")
    print(f"wrote calibration_check.csv, calibration_check.png and calibration_flagged.md to {args.out}",
          file=sys.stderr)
    return 0


def exit_now(code: int) -> NoReturn:
    """End the process at once after a stop, everything already released (the pool's workers ended,
    the staging folder removed): the interpreter's teardown of numpy, polars and matplotlib alone
    takes over a second on a busy machine, and a stop must take less than two. The pool's semaphores
    are released already: ``stop_pool`` ended its manager thread, the last holder of its queues,
    which freed them, so multiprocessing's resource tracker has nothing to warn about (a garbage
    collection here would cost 0.07-0.3 s, measured). Every process still descended from this one
    (a local Ray instance, whole, or one cut in its start-up) is killed, none left orphaned."""
    kill_descendants()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


def evaluate(parser: Parser, args: argparse.Namespace, signals: StopSignals) -> int:
    """Check, run, write the files into a staging folder and swap it onto ``--out`` (``evaluation.outputs``);
    2 when the files cannot be written (``--out`` keeps its earlier files)."""
    try:
        planned = prepare(args)
    except CliError as error:
        parser.error(str(error))
    args.workers, too_many = bounded_workers(args.workers, args.ray)
    for warning in ([too_many] if too_many else []) + cost_warnings(planned, args.agents):
        print(f"{parser.prog}: warning: {warning}", file=sys.stderr, flush=True)
    with tqdm(total=planned.trial_count, unit="trial", disable=None) as bar:
        try:
            table = run_plan(planned, workers=args.workers, progress=bar.update, ray=args.ray)
        except (ExecutorError, TaskError) as error:
            parser.error(str(error))
    try:
        staged = stage_outputs(args.out, planned, table, timing=not args.no_timing, latex=args.latex)
        with signals.held():
            staged.publish()
    except OSError as error:
        print(f"{parser.prog}: error: cannot write the run to {args.out} ({error.strerror or error}); "
              "its earlier files are untouched", file=sys.stderr)
        return 2
    if signals.pending:
        name = signal.Signals(signals.pending).name
        print(f"{parser.prog}: stopped by {name} after the run was written to {args.out}", file=sys.stderr)
        return 128 + signals.pending
    print(staged.summary)
    print(f"wrote the trials, summary, metrics.json, success curve and plots to {args.out}", file=sys.stderr)
    return 0
