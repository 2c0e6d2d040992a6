"""Running an evaluation: the datasets' frames (through the one trial builder, ``evaluation.trials``)
and a sweep of methods and parameters (``evaluation.sweep``) into one per-trial table.

    import evaluation
    table = evaluation.run(["argoverse2"], methods=("cbm", "icp"), grid={"eta": (0.3, 0.6)}, seed=0)
"""
from __future__ import annotations

import dataclasses
from collections import Counter
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import polars as pl

import loaders
from cbm import TrackingParams
from cbm.methods import METHODS
from evaluation import trials
from evaluation.agents import TARGET_DISTANCE
from evaluation.executors import ray_session
from evaluation.scenario import FrameInputs, ScenarioParams
from evaluation.sweep import TIMING_COLUMNS, TRIAL_COLUMNS, Sweep
from evaluation.sweep import run as run_sweep

DEFAULT_METHODS = tuple(name for name, record in METHODS.items() if not (record.takes_peers or record.over_time))
"""Every method, between the references ``none`` and ``oracle``, but ``cbm-graph`` (``--agents`` 3 or
more) and ``cbm-time`` (over a sequence's frames: ``--methods cbm-time``)."""


@dataclass(frozen=True)
class Source:
    """One dataset's part of a run: what the sweep needs of each frame, and the frames skipped."""

    name: str
    inputs: list[FrameInputs]
    skipped: list[int]
    short: list[int] = field(default_factory=list)
    """Frames with fewer CAVs than ``--agents`` asks for (too few vehicles): fewer rows."""


@dataclass(frozen=True)
class Plan:
    """What a run does: the sweep (methods, grid, seed, protocol) over the sources' frames."""

    sweep: Sweep
    sources: tuple[Source, ...]

    @property
    def trial_count(self) -> int:
        """Rows the run gives."""
        return sum(self.sweep.trial_count(len(source.inputs)) for source in self.sources)

    @property
    def most_cavs(self) -> int:
        """The most CAV trials one frame of the run gives (``--agents`` asks for up to ``agents - 1``)."""
        return max((count for source in self.sources for count in Counter(i.index for i in source.inputs).values()),
                   default=0)


def frame_inputs(seq: loaders.Sequence, frames: Iterable[int], protocol: str, cav_distance: float = TARGET_DISTANCE,
                 agents: int = 2, window_s: float = 0.0) -> tuple[list[FrameInputs], list[int]]:
    """What the sweep needs of each frame (``evaluation.trials.frame_inputs``, as the app builds its
    trials), and the frames skipped for want of an ego or a CAV. ``ValueError`` for the OPV2V
    protocol on a dataset that does not say what each agent sees."""
    if protocol == "opv2v" and (seq.visibility is None or seq.visibility["agent_id"].n_unique() < 2):
        raise ValueError(f"--protocol opv2v: {seq.name} does not say what each agent sees; use --protocol range")
    return trials.sequence_inputs(seq, frames, protocol, target_distance=cav_distance, agents=agents, window_s=window_s)


def load_source(name: str, protocol: str, frames: Callable[[int], Sequence[int]] | None = None,
                cav_distance: float = TARGET_DISTANCE, detections: str | None = None, agents: int = 2,
                window_s: float = 0.0) -> Source:
    """Open dataset ``name`` (with a detector's ``detections``, a stage1_boxes.json, when given) and
    make its frame inputs; ``frames(n)`` picks frame indices among ``n`` (default: all); ``window_s``:
    seconds of the frames before each that a late message may come from.
    ``ValueError`` with one line when nothing can be run."""
    try:
        seq = loaders.open(name, detections=detections)
    except ValueError as error:
        raise ValueError(str(error).splitlines()[0]) from None
    picked = range(len(seq)) if frames is None else frames(len(seq))
    nothing = ValueError(f"no chosen frame of {name} has an object to match: there is nothing to calibrate "
                         "(try other --frames, or synthetic:N with N > 0)")
    if not any(len(seq[index].track_ids) for index in picked):
        raise nothing
    inputs, skipped = frame_inputs(seq, picked, protocol, cav_distance, agents, window_s)
    if not inputs:
        raise ValueError(f"no frame of {name} has an ego and a CAV for the {protocol} protocol")
    if not any(len(frame.trial["ids"]) for frame in inputs):
        raise nothing
    return Source(name, inputs, skipped, trials.short_frames(inputs, agents))


def plan(datasets: Sequence[str], *, methods: Sequence[str] = DEFAULT_METHODS,
         grid: Mapping[str, Sequence[Any]] | None = None, seed: int = 0, protocol: str | None = None,
         frames: Callable[[int], Sequence[int]] | None = None, cav_distance: float = TARGET_DISTANCE,
         detections: str | None = None, fusion: str | None = None, agents: int = 2,
         scenario: ScenarioParams | None = None, params: Mapping[str, Any] | None = None,
         tracking: TrackingParams | None = None) -> Plan:
    """Check the run and load its datasets; ``ValueError`` naming what is wrong. ``agents``: the ego
    and ``agents - 1`` CAVs, one trial row per CAV and frame (``evaluation.trials.frame_cav_inputs``).
    ``scenario`` and ``params`` (by ``Method.params_key``) are what the grid does not vary (default:
    ``ScenarioParams()`` and each method's defaults; ``evaluation.presets`` reads them from a preset),
    as is ``tracking``, how a method over time tracks (default: ``TrackingParams()``);
    ``protocol``, when given, replaces the scenario's."""
    if agents < 2:
        raise ValueError(f"--agents must be at least 2 (the ego and one CAV), got {agents}")
    scenario = scenario or ScenarioParams()
    protocol = protocol or scenario.protocol
    sweep = Sweep(methods=tuple(methods), grid=dict(grid or {}), seed=seed, fusion=fusion, params=dict(params or {}),
                  scenario=dataclasses.replace(scenario, protocol=protocol), tracking=tracking or TrackingParams())
    window = late_window(scenario, sweep.grid)
    return Plan(sweep, tuple(load_source(name, protocol, frames, cav_distance, detections, agents, window)
                             for name in datasets))


def late_window(scenario: ScenarioParams, grid: Mapping[str, Sequence[Any]]) -> float:
    """Seconds of frames before each frame that the run's oldest late message needs: the scenario's,
    or the largest the grid asks for."""
    delays = [*grid.get("delay_ms", []), scenario.delay_ms]
    jitters = [*grid.get("jitter_ms", []), scenario.jitter_ms]
    return (max(delays) + max(jitters)) / 1000.0


def run_plan(plan: Plan, *, workers: int = 1, progress: Callable[[int], None] | None = None,
             ray: str | None = None) -> pl.DataFrame:
    """The per-trial table of ``plan``: one row per dataset, frame, grid point and method, in that
    order, with every parameter and metric (``trial_table``). ``ray`` runs it on Ray
    (``evaluation.executors``: ``local``, ``auto`` or a cluster address), one session for every dataset."""
    rows: list[dict[str, Any]] = []
    with ray_session(ray, workers):
        found_by_source = [run_sweep(plan.sweep, source.inputs, workers=workers, progress=progress, ray=ray)
                           for source in plan.sources]
    for source, found in zip(plan.sources, found_by_source):
        rows.extend({"dataset": source.name, **row} for row in found)
    return trial_table(rows, plan.sweep)


def run(datasets: Sequence[str], *, workers: int = 1, progress: Callable[[int], None] | None = None,
        **options: Any) -> pl.DataFrame:
    """Evaluate ``datasets`` (names or paths ``loaders.open`` reads) and return the per-trial table;
    ``options`` are those of ``plan``."""
    return run_plan(plan(datasets, **options), workers=workers, progress=progress)


def trial_table(rows: list[dict[str, Any]], sweep: Sweep) -> pl.DataFrame:
    """The tidy per-trial table: dataset, then the sweep's columns, the runtime last."""
    columns = ["dataset", *sweep.columns()]
    data = {c: [row[c] for row in rows] for c in columns}
    return pl.DataFrame(data, strict=False).with_columns(pl.col(*TRIAL_COLUMNS).cast(pl.Utf8))


def without_timing(table: pl.DataFrame) -> pl.DataFrame:
    """The table without its wall-clock columns: what is byte-identical from run to run."""
    return table.drop(*TIMING_COLUMNS)
