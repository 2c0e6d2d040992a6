"""Scenarios: turn a world-frame object set into one ego/CAV trial.

Protocols: ``sind`` (paper sec. IV-A), ``opv2v`` (sec. V-A) and ``range`` (ours, for data recorded
from one car). Every trial makes all of its random draws, whatever the protocol and parameters, in
this order from one ``numpy.random.Generator``:

1. ``rng.permutation(N)`` -- the order in which the sind protocol deals the objects out;
2. ``rng.standard_normal(3)`` -- the localization error (x, y, yaw), scaled by ``loc_*`` when
   ``localization="gaussian"``, or turned into uniform draws (a point in a disc, a heading) for
   ``"none"`` (unused otherwise: ``"drifting"`` draws from a generator of its own, for the whole
   sequence, ``evaluation.drift``);
3. ``rng.standard_normal((N, 3))`` then ``rng.random(N)`` -- the ego's detection noise (x, y, yaw)
   and heading-flip draw, row ``n`` for input object ``n``;
4. the same for the CAV;
5. ``rng.random(N)`` twice -- the ego's then the CAV's missed-detection draw, row ``n`` for input
   object ``n`` (a detection is missed where its draw is below ``miss_rate``);
6. the false boxes, the ego's then the CAV's: ``rng.random((F, 5))`` each, ``F`` the agent's count
   (``false_box_count``). They come last, so their number changes no draw before them.

So the same (inputs, params, rng) give the same trial bit for bit, and moving one parameter (a
noise level, ``eta``, the protocol) rescales or re-deals the same draws instead of drawing anew.
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from cbm import se2

from .clutter import missed, with_false_boxes
from .delay import MOST_MS, History, delay_rng, message_delay
from .detected import with_detections
from .drift import drift_error
from .localization import reported_cav_pose
from .visibility import agents_see

Protocol = Literal["sind", "opv2v", "range"]
Localization = Literal["fixed", "gaussian", "drifting", "dataset", "none"]


RANGES: dict[str, tuple[float, float]] = {
    "eta": (0.0, 1.0), "sigma_p": (0.0, 3.0), "sigma_theta": (0.0, 45.0), "flip_prob": (0.0, 1.0),
    "loc_x": (-50.0, 50.0), "loc_y": (-50.0, 50.0), "loc_yaw": (-90.0, 90.0), "loc_tau": (1.0, 3600.0),
    "loc_white": (0.0, 1.0), "sensor_range": (10.0, 300.0), "miss_rate": (0.0, 1.0), "false_rate": (0.0, 2.0),
    "min_score": (0.0, 1.0), "sight_share": (0.05, 1.0), "delay_ms": (0.0, MOST_MS), "jitter_ms": (0.0, MOST_MS),
}
"""The one range of each number of a scenario, wherever it is given (a slider, a preset, ``--grid``, a
search space): beyond them a trial takes minutes or means nothing (issue 40: ``false_rate = 50`` made
a frame of 50 false boxes per real one that locked a tab). The localization error is >= 0 unless
``localization="fixed"`` (an offset, either way)."""


@dataclass(frozen=True)
class ScenarioParams:
    """How a trial is made from a scene. Angles in degrees here; radians via the ``*_rad`` properties."""

    protocol: Protocol = "sind"
    eta: float = 0.5
    """Co-visibility rate (sind): ``round(eta * N)`` objects (Python rounding, half to even) are seen by both agents."""
    sigma_p: float = 0.0
    """Metres. Std-dev of the Gaussian detection position noise, on x and on y (sec. IV-A)."""
    sigma_theta: float = 0.0
    """Degrees. Std-dev of the Gaussian detection heading noise (sec. IV-A)."""
    flip_prob: float = 0.5
    """Probability that a detection's heading is turned by pi (sec. IV-A uses 0.5)."""
    localization: Localization = "fixed"
    """``fixed``: the CAV pose is off by exactly (loc_x, loc_y, loc_yaw) (sec. IV-A).
    ``gaussian``: off by zero-mean Gaussians with those std-devs, drawn anew every frame (sec. V-A,
    OpenCOOD's pose noise). ``drifting``: a bias with those std-devs that drifts over time like
    GNSS (a Gauss-Markov process of time constant ``loc_tau``, plus ``loc_white`` white noise,
    ``evaluation.drift``). ``dataset``: the CAV pose the dataset itself reports (OPV2V
    ``predicted_ego_pos``; ``loc_*`` unused). ``none``: no GNSS at all, so no prior: the CAV's frame
    is taken for the ego's (``init`` is the identity) when ``loc_x`` is 0, else the CAV's pose is a
    guess uniform within ``loc_x`` metres of the truth, with any heading (``loc_y``, ``loc_yaw`` unused)."""
    loc_x: float = 3.0
    """Metres. Offset (fixed) or std-dev (gaussian) of the CAV's world x; the radius of the guess (none)."""
    loc_y: float = 3.0
    """Metres. Offset (fixed) or std-dev (gaussian) of the CAV's world y."""
    loc_yaw: float = 5.0
    """Degrees. Offset (fixed) or std-dev (gaussian, drifting) of the CAV's world yaw."""
    loc_tau: float = 60.0
    """Seconds (drifting). Time constant of the bias: frames this far apart share 1/e of it."""
    loc_white: float = 0.1
    """Drifting: white noise added every frame, as a share of each axis's std-dev (GNSS jitter)."""
    sensor_range: float = 50.0
    """Metres (range protocol): an agent sees the objects whose centre is at most this far from it."""
    sight: bool = False
    """Range protocol: an agent sees an object only in its line of sight (``evaluation.sight``: at
    least ``sight_share`` of the footprint not hidden behind nearer boxes), or, where the dataset says
    what the agent saw (Argoverse 2's lidar points for the recording car, per-agent labels), that."""
    sight_share: float = 0.25
    """Least visible share of an object's footprint for an agent to see it (``sight``)."""
    delay_ms: float = 0.0
    """Milliseconds between the CAV's capture and the ego's frame (``evaluation.delay``): the CAV's
    detections and reported pose are those of the sequence at the capture time; with the gap between
    the agents' own timestamps where the dataset has them."""
    jitter_ms: float = 0.0
    """Milliseconds: each frame's delay is ``delay_ms`` plus a uniform draw within +- this."""
    miss_rate: float = 0.0
    """Probability that an agent misses a detection it would make (each agent draws its own misses)."""
    false_rate: float = 0.0
    """False boxes added to each agent's detections: ``round(false_rate * n)`` for ``n`` real detections,
    centres uniform over the agent's sensor disc (range protocol) or the bounding rectangle of its
    detections (sind, opv2v), sizes copied from its real boxes, headings uniform; they pair with nothing."""
    min_score: float = 0.0
    """A real detector's boxes scored below this are dropped (``loaders.detections.DetectedBoxes.above``;
    0 keeps all; no effect on simulated detections or on a detections file without scores)."""
    seed: int = 0
    """Seed of the generator ``make_trial`` uses when it is given none."""

    def __post_init__(self) -> None:
        if self.protocol not in ("sind", "opv2v", "range"):
            raise ValueError(f"ScenarioParams.protocol must be 'sind', 'opv2v' or 'range', got {self.protocol!r}")
        if self.localization not in ("fixed", "gaussian", "drifting", "dataset", "none"):
            raise ValueError("ScenarioParams.localization must be 'fixed', 'gaussian', 'drifting', 'dataset' or "
                             f"'none', got {self.localization!r}")
        for name, (low, high) in RANGES.items():
            _require(self, name, low <= _finite(self, name) <= high, f"a number in [{low:g}, {high:g}]")
        for name in ("loc_x", "loc_y", "loc_yaw"):
            is_valid = getattr(self, name) >= 0.0 or self.localization == "fixed"
            _require(self, name, is_valid, f"a number >= 0 (a std-dev, as localization={self.localization!r})")
        is_seed = isinstance(self.seed, (int, np.integer)) and not isinstance(self.seed, bool) and self.seed >= 0
        _require(self, "seed", is_seed, "an integer >= 0")
        _require(self, "sight", isinstance(self.sight, (bool, np.bool_)), "true or false")
        _require(self, "jitter_ms", self.delay_ms + self.jitter_ms <= MOST_MS,
                 f"at most {MOST_MS:g} - delay_ms (no message older than {MOST_MS:g} ms)")

    @property
    def delayed(self) -> bool:
        """Whether the CAV's messages are late (``delay_ms`` or ``jitter_ms``)."""
        return self.delay_ms > 0.0 or self.jitter_ms > 0.0

    @property
    def window_s(self) -> float:
        """Seconds of frames before a frame that its trial may need (the oldest late message)."""
        return (self.delay_ms + self.jitter_ms) / 1000.0

    @property
    def sigma_theta_rad(self) -> float:
        return math.radians(self.sigma_theta)

    @property
    def loc_yaw_rad(self) -> float:
        return math.radians(self.loc_yaw)


def _finite(params: ScenarioParams, name: str) -> float:
    value = getattr(params, name)
    _require(params, name, isinstance(value, (int, float, np.floating, np.integer)) and not isinstance(value, bool)
             and math.isfinite(value), "a finite number")
    return float(value)


def _require(params: ScenarioParams, name: str, ok: bool, expected: str) -> None:
    if not ok:
        raise ValueError(f"ScenarioParams.{name} must be {expected}, got {getattr(params, name)!r}")


@dataclass(frozen=True)
class Trial:
    """One ego/CAV trial. Both detection lists keep the input order of the objects they contain."""

    ego_boxes: np.ndarray
    """(Ne, 7) noisy detections in the ego frame."""
    cav_boxes: np.ndarray
    """(Nc, 7) noisy detections in the CAV frame."""
    ego_ids: np.ndarray
    """(Ne,) object ids of the ego's detections (dtype of the given ids)."""
    cav_ids: np.ndarray
    """(Nc,) object ids of the CAV's detections."""
    T_true: np.ndarray
    """(3, 3) true CAV->ego transform."""
    init: np.ndarray
    """(3, 3) wrong CAV->ego transform, from the perturbed CAV pose."""
    gt_pairs: np.ndarray
    """(K, 2) int: (ego index, CAV index) of each co-visible object, sorted by ego index."""
    ego_true_xy: np.ndarray
    """(Ne, 2) noise-free centres of the ego's objects, ego frame."""
    cav_true_xy: np.ndarray
    """(Nc, 2) noise-free centres of the CAV's objects, in the ego frame (via ``T_true``)."""
    ego_pose: np.ndarray
    """(3, 3) ego->world."""
    cav_pose: np.ndarray
    """(3, 3) true CAV->world (at capture: ``message_age_s`` before the ego's frame)."""
    message_age_s: float = 0.0
    """Seconds between the CAV's capture and the ego's frame (``evaluation.delay``)."""


def trial_rng(seed: int, frame_index: int, stream: int = 0) -> np.random.Generator:
    """The generator of frame ``frame_index`` under ``seed``: the app and the evaluation share it.
    ``stream`` is the CAV's rank in a frame with several (``evaluation.trials``): rank 0 (the one CAV
    of a two-agent run) draws from ``[seed, frame]`` as it always has, rank ``r`` from
    ``[seed, frame, r]``, an independent stream."""
    return np.random.default_rng([seed, frame_index] if stream == 0 else [seed, frame_index, stream])


@dataclass(frozen=True)
class FrameInputs:
    """What one frame gives every trial made from it: its objects and agents as ``make_trial`` takes
    them (``evaluation.trials.frame_inputs`` makes them from a dataset frame)."""

    index: int
    """Frame index: the trials of this frame draw from ``trial_rng(seed, index)``."""
    trial: Mapping[str, Any]
    """``make_trial`` keyword arguments: ``boxes``, ``ids`` and, as the protocol needs them,
    ``ego_pose``, ``cav_pose``, ``ego_id``, ``cav_id``, ``visibility``, ``cav_reported_pose``."""
    labels: np.ndarray | None = None
    """Class label of each object (same order as ``ids``), for the methods that take labels (VIPS)."""
    note: str = ""
    """How the agents were chosen (e.g. ``auto``), for the people reading the result."""
    detections: Mapping[str, Any] | None = None
    """A real detector's boxes of ``"ego"`` and / or ``"cav"`` (``loaders.detections.DetectedBoxes``,
    each in its agent's frame): those scored at least ``min_score`` replace that agent's simulated
    detections (``evaluation.detected.with_detections``)."""
    stream: int = 0
    """The CAV's rank among the frame's CAVs: its trial draws from ``trial_rng(seed, index, stream)``."""
    cohort: tuple[FrameInputs, ...] = ()
    """The inputs of every CAV of the frame, this one among them (more than two agents): one tuple
    shared by the frame's inputs, so a frame of K CAVs holds K references, not K squared."""
    times: np.ndarray | None = None
    """Seconds: the timestamps of every frame of the sequence (one array shared by its frames), for
    a localization error that drifts over time (``evaluation.drift``)."""
    cav: str = ""
    """The CAV's id (empty for abstract agents): its drift is its own."""
    history: History | None = None
    """The frames before this one as the CAV saw them, for a late message (``evaluation.delay``);
    None when the scenario asked for none (``frame_inputs``' ``window_s``)."""
    gap_s: float = 0.0
    """Seconds by which the CAV's own capture precedes the ego's in the dataset (its timestamps)."""

    @property
    def peers(self) -> tuple[FrameInputs, ...]:
        """The inputs of the frame's other CAVs, for the joint pose estimate."""
        return tuple(other for other in self.cohort if other.stream != self.stream)

    def build(self, params: ScenarioParams, seed: int) -> Trial:
        """The trial of this frame under ``params`` and ``seed``: every trial of the app, the
        evaluation, sweeps and search is made here."""
        trial = make_trial(**self.late(params, seed), params=params, rng=trial_rng(seed, self.index, self.stream),
                           loc_error=self.drift(params, seed))
        if not self.detections:
            return trial
        agents = {"ego": self.trial.get("ego_id"), "cav": self.trial.get("cav_id")}
        kept = {role: found.above(params.min_score).boxes for role, found in self.detections.items()}
        return with_detections(trial, kept, self.trial["boxes"], self.trial["ids"], agents)

    def late(self, params: ScenarioParams, seed: int) -> Mapping[str, Any]:
        """``make_trial``'s arguments with the CAV's objects and pose at its capture time, the
        dataset's own gap plus the scenario's delay before this frame (``History.at``); as they are
        when the message is not late."""
        if not params.delayed and self.gap_s == 0.0:
            return self.trial
        if self.history is None:
            raise ValueError("a late message needs the frames before this one (frame_inputs(..., window_s=...))")
        age = self.gap_s + (message_delay(params.delay_ms, params.jitter_ms, delay_rng(seed, self.index, self.stream))
                            if params.delayed else 0.0)
        cav_world, cav_pose, captured = self.history.at(self.history.times[-1] - age)
        return {**self.trial, "cav_world": cav_world, "cav_pose": cav_pose,
                "message_age_s": float(self.history.times[-1] - captured)}

    def drift(self, params: ScenarioParams, seed: int) -> np.ndarray | None:
        """This frame's drifting localization error (None unless ``localization="drifting"``)."""
        if params.localization != "drifting":
            return None
        if self.times is None:
            raise ValueError("localization 'drifting' needs the frames' timestamps (a sequence of frames)")
        sigma = np.array([params.loc_x, params.loc_y, params.loc_yaw_rad])
        return drift_error(sigma, params.loc_tau, params.loc_white, seed, self.cav or str(self.stream), self.times,
                           self.index)

    def peer_trials(self, params: ScenarioParams, seed: int) -> list[Trial]:
        """The trials of the frame's other CAVs, as their own rows build them."""
        return [peer.build(params, seed) for peer in self.peers]


def make_trial(
    boxes: np.ndarray,
    ids: np.ndarray,
    params: ScenarioParams,
    *,
    ego_pose: np.ndarray | None = None,
    cav_pose: np.ndarray | None = None,
    cav_id: object | None = None,
    ego_id: object | None = None,
    visibility: Mapping[str, np.ndarray] | None = None,
    cav_reported_pose: np.ndarray | None = None,
    rng: np.random.Generator | None = None,
    loc_error: np.ndarray | None = None,
    cav_world: np.ndarray | None = None,
    message_age_s: float = 0.0,
) -> Trial:
    """Make one trial from ``(N, 7)`` world-frame ``boxes`` with unique ``ids``.

    sind: missing poses default to the objects' centroid with yaw 0. opv2v: both poses and
    ``visibility`` (``{"ego": ids, "cav": ids}``) are required. range: both poses are required.
    ``visibility`` is read by opv2v only; ``cav_reported_pose`` (the dataset's own CAV pose) by
    ``localization="dataset"`` only, which needs it. In every protocol an agent whose id is given never
    detects itself (removed after the deal, so sind counts hold for objects other than the agents).
    ``rng`` defaults to ``np.random.default_rng(params.seed)``; the draw order is in the module docstring.
    ``loc_error`` is the drifting localization error of this frame (``FrameInputs.drift``), which
    ``localization="drifting"`` needs. ``cav_world``: the same objects (rows of ``boxes``) where the
    CAV saw them, ``message_age_s`` before (a late message, ``FrameInputs.late``; NaN rows: not there
    then), with ``cav_pose`` the CAV's pose at that time.
    """
    boxes, ids = _checked_objects(boxes, ids)
    rng = np.random.default_rng(params.seed) if rng is None else rng
    ego_pose, cav_pose = _poses(boxes, params.protocol, ego_pose, cav_pose)

    n = len(boxes)
    order = rng.permutation(n)
    loc_draw = rng.standard_normal(3)
    ego_noise = (rng.standard_normal((n, 3)), rng.random(n))
    cav_noise = (rng.standard_normal((n, 3)), rng.random(n))
    ego_missed, cav_missed = missed(rng.random(n), params.miss_rate), missed(rng.random(n), params.miss_rate)

    cav_world = boxes if cav_world is None else np.asarray(cav_world, dtype=float)
    ego_sees, cav_sees = agents_see(boxes, cav_world, ids, params, order, ego_pose, cav_pose, visibility)
    ego_sees &= ~ego_missed if ego_id is None else ~ego_missed & (ids != ego_id)
    cav_sees &= ~cav_missed if cav_id is None else ~cav_missed & (ids != cav_id)

    T_true = se2.inverse(ego_pose) @ cav_pose
    reported = reported_cav_pose(params, ego_pose, cav_pose, loc_draw, cav_reported_pose, loc_error)
    init = se2.inverse(ego_pose) @ reported
    ego_frame_boxes = se2.apply_boxes(se2.inverse(ego_pose), boxes[ego_sees])
    cav_frame_boxes = se2.apply_boxes(se2.inverse(cav_pose), cav_world[cav_sees])
    trial = Trial(
        ego_boxes=_detect(ego_frame_boxes, ego_noise[0][ego_sees], ego_noise[1][ego_sees], params),
        cav_boxes=_detect(cav_frame_boxes, cav_noise[0][cav_sees], cav_noise[1][cav_sees], params),
        ego_ids=ids[ego_sees],
        cav_ids=ids[cav_sees],
        T_true=T_true,
        init=init,
        gt_pairs=co_visible_pairs(ego_sees, cav_sees),
        ego_true_xy=ego_frame_boxes[:, :2].copy(),
        cav_true_xy=se2.apply_points(T_true, cav_frame_boxes[:, :2]),
        ego_pose=ego_pose,
        cav_pose=cav_pose,
        message_age_s=message_age_s,
    )
    if params.false_rate == 0.0:
        return trial
    return with_false_boxes(trial, rng, params.false_rate, params.sensor_range if params.protocol == "range" else None)


def _checked_objects(boxes: np.ndarray, ids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    boxes = np.asarray(boxes, dtype=float)
    ids = np.asarray(ids)
    if boxes.size == 0:
        boxes = boxes.reshape(0, 7)
    if boxes.ndim != 2 or boxes.shape[1] != 7:
        raise ValueError(f"boxes must be an (N, 7) array, got shape {boxes.shape}")
    if ids.shape != (len(boxes),):
        raise ValueError(f"ids must have shape ({len(boxes)},) like boxes, got {ids.shape}")
    if len(np.unique(ids)) != len(ids):
        raise ValueError("ids must be unique: they identify the objects of the ground-truth pairs")
    return boxes, ids


def _poses(
    boxes: np.ndarray, protocol: Protocol, ego_pose: np.ndarray | None, cav_pose: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray]:
    if protocol == "sind":
        centre = boxes[:, :2].mean(axis=0) if len(boxes) else np.zeros(2)
        default = se2.make(centre[0], centre[1], 0.0)
        ego_pose = default if ego_pose is None else ego_pose
        cav_pose = default if cav_pose is None else cav_pose
    elif ego_pose is None or cav_pose is None:
        raise ValueError(f"the {protocol} protocol needs both ego_pose and cav_pose (agent->world)")
    return _checked_pose("ego_pose", ego_pose), _checked_pose("cav_pose", cav_pose)


def _checked_pose(name: str, pose: np.ndarray) -> np.ndarray:
    pose = np.asarray(pose, dtype=float)
    if pose.shape != (3, 3):
        raise ValueError(f"{name} must be a (3, 3) SE(2) matrix, got shape {pose.shape}")
    return pose.copy()


def _detect(boxes: np.ndarray, gauss: np.ndarray, uniform: np.ndarray, params: ScenarioParams) -> np.ndarray:
    """Detection noise (sec. IV-A): N(0, sigma_p) on x and y, N(0, sigma_theta) on yaw, a pi flip with flip_prob."""
    noisy = boxes.copy()
    noisy[:, :2] += params.sigma_p * gauss[:, :2]
    flips = np.pi * (uniform < params.flip_prob)
    noisy[:, 6] = se2.wrap_angle(noisy[:, 6] + params.sigma_theta_rad * gauss[:, 2] + flips)
    return noisy


def co_visible_pairs(ego_sees: np.ndarray, cav_sees: np.ndarray) -> np.ndarray:
    """(K, 2) (ego index, CAV index) of the objects both agents see, sorted by ego index."""
    both = ego_sees & cav_sees
    ego_index = np.cumsum(ego_sees) - 1
    cav_index = np.cumsum(cav_sees) - 1
    return np.stack([ego_index[both], cav_index[both]], axis=1).astype(np.int64)
