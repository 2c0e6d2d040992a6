"""Parameter sweeps: trials over frames and a grid of parameters, every method on every trial, one
row of metrics per (frame, grid point, method).

    from evaluation.scenario import FrameInputs
    from evaluation.sweep import Sweep, run
    sweep = Sweep(methods=("cbm", "icp"), grid={"eta": [0.2, 0.6], "sigma2": [2.0, 3.0]}, seed=0)
    rows = run(sweep, [FrameInputs(0, {"boxes": boxes, "ids": ids})], workers=2)

A grid name is a field of :class:`~evaluation.scenario.ScenarioParams` (it changes the trial), a tunable
parameter of one or more methods (``cbm.methods``; it changes only those methods' runs), or
``tracking.<field>``, a field of ``cbm.TrackingParams`` (``tracking.gate``: it changes only the
methods over time's runs, which record every tracking field in ``tracking.<field>`` columns).
Every trial is built by ``FrameInputs.build`` (frame ``k`` draws from ``trial_rng(seed, k)``), as
the app builds its trials, so any row can be reproduced there from its frame, parameters and seed.
A method that calibrates over time (``cbm-time``: ``Method.over_time``) runs the frames of each CAV
in time order, one task per sequence and CAV. Rows come in order -- frame, scenario grid point,
method, method grid point, each in the order given -- whatever the number of workers.
"""
from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cbm import SequenceCalibrator, TrackingParams
from cbm.methods import METHODS

from .detected import FALSE_POSITIVE_CLASS
from .executors import run_tasks
from .fusion import FUSION_COLUMNS, FUSIONS, fusion_columns, fusion_pose
from .metric_registry import TRIAL_METRICS, aggregate
from .metrics import TrialMetrics, evaluate, is_success, rre, rte
from .scenario import FrameInputs, ScenarioParams, Trial

SCENARIO_FIELDS = tuple(f.name for f in dataclasses.fields(ScenarioParams))
"""Scenario parameter columns, ``seed`` included (it is the sweep's seed)."""
TRACKING_FIELDS = {f"tracking.{f.name}": f.name for f in dataclasses.fields(TrackingParams)}
"""Grid names and columns of the tracking parameters of a method over time, by their field."""
TRIAL_COLUMNS = ("ego_id", "cav_id")
TIMING_COLUMNS = ("runtime_s",)
"""Wall-clock seconds of the method: the only columns that differ between two runs of one sweep."""
RECORD_COLUMNS = tuple(f.name for f in dataclasses.fields(TrialMetrics) if f.name not in TIMING_COLUMNS)


def metric_columns() -> tuple[str, ...]:
    """Per-trial metric columns: the trial's record (``evaluation.metrics.TrialMetrics`` without the
    runtime), every other metric of ``evaluation.metric_registry.TRIAL_METRICS``, ``is_success``, and
    the RRE/RTE of ``init`` (the pose before calibration)."""
    return (*RECORD_COLUMNS, *(key for key in TRIAL_METRICS if key not in RECORD_COLUMNS),
            "success", "init_rre", "init_rte")


@dataclass(frozen=True)
class Sweep:
    """What to run: methods, a grid (name -> values), a seed and the fixed scenario settings."""

    methods: tuple[str, ...]
    grid: Mapping[str, Sequence[Any]] = field(default_factory=dict)
    seed: int = 0
    scenario: ScenarioParams = ScenarioParams()
    """Scenario settings the grid does not vary (its ``seed`` is replaced by the sweep's)."""
    params: Mapping[str, Any] = field(default_factory=dict)
    """Method parameters the grid does not vary, by ``Method.params_key`` (a preset's); a method
    missing here starts from its defaults."""
    fusion: str | None = None
    """``nms``: each row also holds its late-fusion detections (``evaluation.fusion.FUSION_COLUMNS``)."""
    tracking: TrackingParams = TrackingParams()
    """How the methods over time track where the grid does not vary it (a preset's ``[tracking]``)."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "methods", tuple(self.methods))
        object.__setattr__(self, "grid", {name: tuple(values) for name, values in self.grid.items()})
        unknown = [m for m in self.methods if m not in METHODS]
        if not self.methods or unknown:
            raise ValueError(f"methods must be a non-empty selection of {sorted(METHODS)}, got {list(self.methods)}")
        if len(set(self.methods)) != len(self.methods):
            raise ValueError(f"methods must not repeat, got {list(self.methods)}")
        if self.fusion not in (None, *FUSIONS):
            raise ValueError(f"fusion must be one of {FUSIONS} or None, got {self.fusion!r}")
        for name, values in self.grid.items():
            self._check_grid_name(name)
            if not values:
                raise ValueError(f"grid parameter {name!r} has no values")
        self.scenario_points()
        self.tracking_points()
        for method in self.methods:
            self.method_points(method)

    def _check_grid_name(self, name: str) -> None:
        if name == "seed":
            raise ValueError("seed is the sweep's own argument, not a grid parameter")
        if name in SCENARIO_FIELDS:
            return
        if name in TRACKING_FIELDS:
            if not self.over_time():
                over_time = ", ".join(m for m in METHODS if METHODS[m].over_time)
                raise ValueError(f"grid parameter {name!r} is a tracking parameter of a method over time "
                                 f"({over_time}); select one")
            return
        if not any(name in METHODS[m].tunable for m in self.methods):
            owners = [m for m in METHODS if name in METHODS[m].tunable]
            where = (f"a parameter of {', '.join(owners)}, none of which is selected" if owners
                     else "not a parameter of the scenario or of any method")
            raise ValueError(f"grid parameter {name!r} is {where}")

    def scenario_points(self) -> list[ScenarioParams]:
        """The scenario of every point of the scenario part of the grid, in grid order."""
        names = [n for n in self.grid if n in SCENARIO_FIELDS]
        base = dataclasses.replace(self.scenario, seed=self.seed)
        return [dataclasses.replace(base, **dict(zip(names, values)))
                for values in itertools.product(*(self.grid[n] for n in names))]

    def over_time(self) -> bool:
        """Whether a selected method calibrates over time (and so reads the tracking parameters)."""
        return any(METHODS[m].over_time for m in self.methods)

    def tracking_points(self) -> list[TrackingParams]:
        """The tracking parameters at every point of the tracking part of the grid, in grid order."""
        names = [n for n in self.grid if n in TRACKING_FIELDS]
        return [dataclasses.replace(self.tracking, **{TRACKING_FIELDS[n]: v for n, v in zip(names, values)})
                for values in itertools.product(*(self.grid[n] for n in names))]

    def points(self, method: str) -> list[tuple[Any, TrackingParams | None]]:
        """``method``'s parameters and, for a method over time, its tracking parameters at every point
        of its part of the grid, in grid order."""
        tracking = self.tracking_points() if METHODS[method].over_time else [None]
        return list(itertools.product(self.method_points(method), tracking))

    def method_points(self, method: str) -> list[Any]:
        """``method``'s parameters at every point of its part of the grid, in grid order, as it runs
        them (forced parameters applied, so the table records what ran)."""
        record = METHODS[method]
        names = [n for n in self.grid if n in record.tunable]
        base = self.params.get(record.params_key) or record.params()
        return [record.resolved(dataclasses.replace(base, **dict(zip(names, values))))
                for values in itertools.product(*(self.grid[n] for n in names))]

    def trial_count(self, n_frames: int) -> int:
        """Rows a run over ``n_frames`` frames gives."""
        return n_frames * len(self.scenario_points()) * sum(len(self.points(m)) for m in self.methods)

    def parameter_columns(self) -> list[str]:
        """Scenario fields, then every field of the selected methods' parameters (first use first),
        then the tracking parameters when a method calibrates over time."""
        method_columns = dict.fromkeys(f.name for m in self.methods for f in dataclasses.fields(METHODS[m].params))
        return [*SCENARIO_FIELDS, *method_columns, *(TRACKING_FIELDS if self.over_time() else ())]

    def columns(self) -> list[str]:
        """Every column of a row, in order: frame, method, parameters, agents, metrics, timing."""
        fused = FUSION_COLUMNS if self.fusion else ()
        return ["frame", "method", *self.parameter_columns(), *TRIAL_COLUMNS, *metric_columns(), *fused,
                *TIMING_COLUMNS]


def grid_defaults(methods: Iterable[str]) -> dict[str, Any]:
    """Every parameter a grid over ``methods`` may name, with its default (its type parses values)."""
    defaults = {f.name: f.default for f in dataclasses.fields(ScenarioParams) if f.name != "seed"}
    for method in methods:
        defaults.update({f.name: f.default for f in dataclasses.fields(METHODS[method].params)
                         if f.name in METHODS[method].tunable})
        if METHODS[method].over_time:
            defaults.update({name: getattr(TrackingParams(), field) for name, field in TRACKING_FIELDS.items()})
    return defaults


def calibrator_for(method: str, params: Any, tracking: TrackingParams) -> SequenceCalibrator:
    """A fresh calibrator over time for ``method`` (``over_time`` methods), with ``params`` as it runs
    them and ``tracking`` (an offline method's answers at the end: ``cbm.sequence.Smoother``)."""
    return METHODS[method].calibrator(params, tracking)


def run(sweep: Sweep, frames: Sequence[FrameInputs], *, workers: int = 1,
        progress: Callable[[int], None] | None = None, ray: str | None = None) -> list[dict[str, Any]]:
    """Every row of ``sweep`` over ``frames``, in order. ``workers > 1`` runs the tasks -- one per
    (frame, scenario point) for the methods that take frames alone, one per (CAV, scenario point)
    over all of its frames for those over time -- in a process pool, ``ray`` (``local``, ``auto`` or an
    address) on Ray (``evaluation.executors``); ``progress(n)`` is called as ``n`` rows finish. A task
    that raises stops the run with a ``evaluation.executors.TaskError`` naming its frames and scenario
    point. The frames' other CAVs travel with each task only when a method takes them (``cbm-graph``)."""
    if not any(METHODS[m].takes_peers for m in sweep.methods):
        frames = [dataclasses.replace(frame, cohort=()) for frame in frames]
    points = list(enumerate(sweep.scenario_points()))
    tasks = []
    if any(not METHODS[m].over_time for m in sweep.methods):
        tasks += [(sweep, (position,), (frame,), point, False) for position, frame in enumerate(frames)
                  for point in points]
    if any(METHODS[m].over_time for m in sweep.methods):
        tasks += [(sweep, positions, chain, point, True) for positions, chain in _by_cav(frames) for point in points]
    done = progress or (lambda n: None)
    results = run_tasks(run_task, tasks, workers=workers, ray=ray, done=lambda rows: done(len(rows)),
                        name=lambda task: task_name(*task))
    return [row for _, row in sorted((item for rows in results for item in rows), key=lambda item: item[0])]


def _by_cav(frames: Sequence[FrameInputs]) -> list[tuple[tuple[int, ...], tuple[FrameInputs, ...]]]:
    """The frames of each CAV (by its rank among a frame's CAVs), in frame order, with their
    positions in ``frames``: the chains a calibrator over time steps through."""
    chains: dict[int, list[int]] = {}
    for position, frame in enumerate(frames):
        chains.setdefault(frame.stream, []).append(position)
    ordered = [sorted(positions, key=lambda p: frames[p].index) for positions in chains.values()]
    return [(tuple(positions), tuple(frames[p] for p in positions)) for positions in ordered]


def task_name(sweep: Sweep, positions: tuple[int, ...], frames: tuple[FrameInputs, ...],
              point: tuple[int, ScenarioParams], over_time: bool) -> str:
    """A task as the user knows it: its frames and the scenario grid's values."""
    scenario = point[1]
    values = ", ".join(f"{n}={getattr(scenario, n)}" for n in sweep.grid if n in SCENARIO_FIELDS)
    where = (f"frames {frames[0].index}-{frames[-1].index} in time order" if over_time
             else f"frame {frames[0].index}")
    return where + (f" ({values})" if values else "")


def run_task(sweep: Sweep, positions: tuple[int, ...], frames: tuple[FrameInputs, ...],
             point: tuple[int, ScenarioParams], over_time: bool) -> list[tuple[tuple, dict[str, Any]]]:
    """The rows of one task, each with the key that puts it in the sweep's order: the frame's
    position, the scenario point, the method and its grid point. A frame alone runs every method that
    takes frames alone; a chain of frames runs the methods over time, each grid point with a
    calibrator of its own stepping through the frames in time order (an offline method's answers,
    ``cbm-smooth``'s, come once every frame is in)."""
    number, scenario = point
    methods = [(k, m) for k, m in enumerate(sweep.methods) if METHODS[m].over_time == over_time]
    calibrators = {(k, j): calibrator_for(m, params, tracking) for k, m in methods if over_time
                   for j, (params, tracking) in enumerate(sweep.points(m))}
    made = []
    for position, frame in zip(positions, frames):
        trial = frame.build(scenario, sweep.seed)
        peers = frame.peer_trials(scenario, sweep.seed) if any(METHODS[m].takes_peers for _, m in methods) else []
        for k, method in methods:
            for j, (params, tracking) in enumerate(sweep.points(method)):
                if over_time:
                    result = calibrators[k, j].step(trial.ego_boxes, trial.cav_boxes, trial.init, frame_time(frame),
                                                    agent=frame.trial.get("cav_id"))
                else:
                    result = run_method(method, trial, params, frame, peers)
                made.append(((position, number, k, j), (frame, method, params, tracking, trial, result)))
    final = {key: iter(calibrator.smoothed()) for key, calibrator in calibrators.items()
             if METHODS[sweep.methods[key[0]]].offline}
    rows = []
    for key, (frame, method, params, tracking, trial, result) in made:
        result = next(final[key[2:]]) if key[2:] in final else result
        rows.append((key, trial_row(sweep, frame, scenario, method, (params, tracking), trial, result)))
    return rows


def trial_row(sweep: Sweep, frame: FrameInputs, scenario: ScenarioParams, method: str,
              point: tuple[Any, TrackingParams | None], trial: Trial, result: Any) -> dict[str, Any]:
    """The row of ``method``'s ``result`` on ``trial``, the trial of ``frame`` under ``scenario``, at its
    grid ``point`` (``Sweep.points``): every column of ``sweep.columns()``, the fused detections when
    the sweep asks for them. Every row of a run is made here, and so is a row of a result computed
    elsewhere (a frame the app computed), which then reads as the run's."""
    params, tracking = point
    base = {"frame": frame.index, **dataclasses.asdict(scenario),
            "ego_id": _text(frame.trial.get("ego_id")), "cav_id": _text(frame.trial.get("cav_id"))}
    init_error = {"init_rre": rre(trial.init, trial.T_true), "init_rte": rte(trial.init, trial.T_true)}
    row = _row(sweep, base, method, params, tracking, evaluate(result, trial), init_error)
    if sweep.fusion:
        row.update(fusion_columns(trial, fusion_pose(method, result, trial), frame, sweep.seed))
    return row


def frame_time(frame: FrameInputs) -> float:
    """Seconds: the frame's timestamp, or its index at 10 Hz when its sequence gives none."""
    return float(frame.times[frame.index]) if frame.times is not None else 0.1 * frame.index


def run_method(method: str, trial: Trial, params: Any, frame: FrameInputs, peers: Sequence[Trial] = ()) -> Any:
    """``method`` on ``trial`` with what it takes: the objects' labels (when the frame has them; a
    detector's false positive is a vehicle), the trial's true pairs and the frame's other CAV trials."""
    labels = None
    if frame.labels is not None:
        label_of = dict(zip(np.asarray(frame.trial["ids"]).tolist(), np.asarray(frame.labels).tolist()))
        labels = (np.array([label_of.get(i, FALSE_POSITIVE_CLASS) for i in trial.ego_ids.tolist()]),
                  np.array([label_of.get(i, FALSE_POSITIVE_CLASS) for i in trial.cav_ids.tolist()]))
    return METHODS[method](trial.ego_boxes, trial.cav_boxes, trial.init, params, labels=labels,
                           true_pairs=trial.gt_pairs, peers=peers)


def _row(sweep: Sweep, base: dict[str, Any], method: str, params: Any, tracking: TrackingParams | None,
         metrics: TrialMetrics, init_error: dict[str, float]) -> dict[str, Any]:
    """One table row: every column of ``sweep.columns()``, None for other methods' parameters (and
    for the tracking parameters of a method that takes each frame alone)."""
    row = dict.fromkeys(sweep.columns())
    row.update(base)
    row.update(method=method, **dataclasses.asdict(params), success=is_success(metrics), **init_error)
    if tracking is not None:
        row.update({name: getattr(tracking, field) for name, field in TRACKING_FIELDS.items()})
    row.update(dataclasses.asdict(metrics))
    row.update({key: metric.of(metrics) for key, metric in TRIAL_METRICS.items()})
    return row


def _text(value: Any) -> str | None:
    return None if value is None else str(value)


def summarise(rows: Sequence[Mapping[str, Any]], by: Sequence[str]) -> list[tuple[tuple, dict[str, float]]]:
    """The aggregates (``evaluation.metric_registry.aggregate``) of the rows grouped by the columns
    ``by``: ``(key, aggregate)`` per group, groups in order of first appearance. A column an older
    run's table lacks (``abstained``) takes its default."""
    groups: dict[tuple, list[TrialMetrics]] = {}
    names = [f.name for f in dataclasses.fields(TrialMetrics)]
    for row in rows:
        groups.setdefault(tuple(row[c] for c in by), []).append(TrialMetrics(**{n: row[n] for n in names if n in row}))
    return [(key, aggregate(metrics)) for key, metrics in groups.items()]
