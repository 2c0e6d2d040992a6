"""Real detections: CoAlign / HEAL ``stage1_boxes.json`` (per-agent boxes of a first-stage detector)
attached to the frames of their OPV2V / V2XSet / V2V4Real / DAIR-V2X dataset.

    seq = loaders.open("OPV2V/test/2021_08_18_19_48_05", detections="stage1_boxes.json")
    seq[0].detections["641"].boxes        # (N, 7) in agent 641's own LiDAR frame

The file is what CoAlign's ``opencood/tools/pose_graph_pre_calc.py`` saves: a JSON object keyed by
OpenCOOD sample index (a string), each value ``null`` (no box) or an object with

- ``cav_id_list``: the agents of the sample, the ego first;
- ``pred_corner3d_np_list``: per agent, ``(N, 8, 3)`` box corners in that agent's own LiDAR frame
  (not projected to the ego), in OpenCOOD's corner order (``boxes_to_corners_3d``: bottom face
  front-left, front-right, rear-right, rear-left, then the top face in the same order);
- ``uncertainty_np_list``: per agent, ``(N, D)`` the uncertainty head's output for each box
  (D = 2 for x, y, 3 with yaw); kept as saved (a missing key gives ``D = 0``);
- ``pred_score_np_list`` (optional): per agent, ``(N,)`` the detector's confidence in each box,
  kept as ``DetectedBoxes.scores`` (None without the key: then no score threshold applies,
  ``DetectedBoxes.above``);
- ``lidar_pose_clean_np``: per agent, the true LiDAR pose ``[x, y, z, roll, yaw, pitch]``
  (metres, degrees); ``lidar_pose_np`` (the noisy one, in some forks) is not needed.

Sample indices count the frames of a whole split, so each sample is matched to a frame by pose:
the sample's ego (``cav_id_list[0]``) must be an agent of the frame, at ``lidar_pose_clean_np[0]``
within :data:`POSE_TOLERANCE` metres. Samples that match no frame are ignored; a file of which no
sample matches is refused, and so is a sample whose CAVs are not agents of its frame. Of two samples
matching one frame (an ego standing still) the first is kept and a warning names the others. The
file is read one sample at a time (``loaders.structured.json_object_items``): files of hundreds of
megabytes take the memory of their matched boxes, not gigabytes of parsed JSON.
DAIR-V2X agents ``0`` / ``1`` are ``vehicle`` / ``infrastructure``.

Boxes are fitted to the corners (centre = mean corner, length and yaw from the front and rear
edge midpoints, width from the side midpoints, height from the faces) and expressed in the agent's
LiDAR frame, right-handed: OPV2V / V2XSet (CARLA, left-handed) have y and yaw mirrored, as the
OPV2V loader does for the world.
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import LoaderError, shown
from .scene import Sequence
from .structured import field, json_object_items, numbers

POSE_TOLERANCE = 0.05
"""Metres between a sample's ego pose and the frame's agent pose for them to be the same frame."""
DAIR_AGENTS = {"0": "vehicle", "1": "infrastructure"}
CORNERS = "N boxes of 8 corners of 3 numbers"
MAX_COORDINATE = 1e5
"""Metres: a corner farther than this from its agent's LiDAR is not a detection (finite values as
large as 1e300 would overflow the box fit and fail a trial later, far from the file)."""


@dataclass(frozen=True)
class DetectedBoxes:
    """One agent's detections in one frame."""

    boxes: np.ndarray
    """(N, 7) ``x, y, z, length, width, height, yaw`` in the agent's LiDAR frame (right-handed)."""
    uncertainty: np.ndarray
    """(N, D) the detector's uncertainty per box, as saved."""
    scores: np.ndarray | None = None
    """(N,) the detector's confidence per box, or None when the file has no ``pred_score_np_list``."""

    def above(self, threshold: float) -> DetectedBoxes:
        """The boxes scored at least ``threshold`` (all of them without scores, or at threshold 0)."""
        if self.scores is None or threshold <= 0:
            return self
        keep = self.scores >= threshold
        return DetectedBoxes(self.boxes[keep], self.uncertainty[keep], self.scores[keep])


def attach(sequence: Sequence, path: Path) -> Sequence:
    """Read ``path`` (streamed: one sample in memory at a time) and set ``sequence.detections``
    (frame index -> agent id -> boxes); returns it. A sample whose agents are not all in its frame
    is refused; of two samples matching one frame the first is kept, with a warning."""
    left_handed = sequence.name.startswith("opv2v/")
    poses = _agent_positions(sequence)
    found: dict[int, dict[str, DetectedBoxes]] = {}
    kept: dict[int, str] = {}
    repeated: list[str] = []
    for key, sample in json_object_items(path, "a JSON object of sample index -> detections"):
        if sample is None:
            continue
        agents = _agent_ids(path, key, sample, sequence)
        pose = numbers(path, _nth(path, key, sample, "lidar_pose_clean_np", 0), f"{key}.lidar_pose_clean_np[0]", 6)
        frame = _frame_at(poses.get(agents[0]), pose[0], -pose[1] if left_handed else pose[1])
        if frame is None:
            continue
        if frame in kept:
            repeated.append(f"{key} (frame {frame}, kept {kept[frame]})")
            continue
        _check_agents_in_frame(path, key, agents, sequence, frame)
        found[frame], kept[frame] = _sample_boxes(path, key, sample, agents, left_handed), key
    if not found:
        raise LoaderError(f"{path}: no sample matches a frame of {sequence.name} (each sample's "
                          f"lidar_pose_clean_np[0] against its ego's pose, within {POSE_TOLERANCE} m)")
    if repeated:
        _warn(sequence, f"{path}: {len(repeated)} sample(s) match a frame an earlier sample matched (the same ego "
                        f"pose), and were left out: {', '.join(repeated[:3])}{' …' if len(repeated) > 3 else ''}")
    sequence.detections = found
    return sequence


def _check_agents_in_frame(path: Path, key: str, agents: list[str], sequence: Sequence, frame: int) -> None:
    """``LoaderError`` unless every agent of the sample is an agent of ``frame``: a missing CAV's
    detected boxes would otherwise be mixed with simulated ones."""
    present = set(sequence[frame].agents["agent_id"].cast(str).to_list())
    missing = [agent for agent in agents if agent not in present]
    if missing:
        raise LoaderError(f"{path}: {key}.cav_id_list: agent {missing[0]!r} is not in frame {frame} of "
                          f"{sequence.name} (its agents: {', '.join(sorted(present))}); the sample belongs to "
                          f"another dataset or split")


def _warn(sequence: Sequence, note: str) -> None:
    """A warning in ``sequence.warnings`` (for the app) and as a ``UserWarning``."""
    sequence.warnings.append(note)
    warnings.warn(note, UserWarning, stacklevel=3)


def fit_boxes(corners: np.ndarray) -> np.ndarray:
    """``(N, 7)`` boxes fitted to ``(N, 8, 3)`` corners in OpenCOOD's order."""
    corners = np.asarray(corners, dtype=float).reshape(-1, 8, 3)
    front, rear = corners[:, [0, 1]].mean(axis=1), corners[:, [2, 3]].mean(axis=1)
    left, right = corners[:, [0, 3]].mean(axis=1), corners[:, [1, 2]].mean(axis=1)
    along = front[:, :2] - rear[:, :2]
    return np.column_stack([
        corners.mean(axis=1),
        np.linalg.norm(along, axis=1),
        np.linalg.norm(left[:, :2] - right[:, :2], axis=1),
        corners[:, 4:, 2].mean(axis=1) - corners[:, :4, 2].mean(axis=1),
        np.arctan2(along[:, 1], along[:, 0]),
    ])


def _agent_positions(sequence: Sequence) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """``agent id -> (frame indices, (K, 2) positions)`` over the sequence."""
    rows: dict[str, list[tuple[int, float, float]]] = {}
    for frame in sequence:
        agents = frame.agents
        if agents is None:
            continue
        for agent, x, y in agents.select("agent_id", "x", "y").iter_rows():
            rows.setdefault(agent, []).append((frame.index, x, y))
    return {agent: (np.array([r[0] for r in got]), np.array([r[1:] for r in got])) for agent, got in rows.items()}


def _frame_at(positions: tuple[np.ndarray, np.ndarray] | None, x: float, y: float) -> int | None:
    """The frame whose agent is at ``(x, y)`` within the tolerance, or None."""
    if positions is None:
        return None
    frames, xy = positions
    gap = np.linalg.norm(xy - [x, y], axis=1)
    best = int(np.argmin(gap))
    return int(frames[best]) if gap[best] <= POSE_TOLERANCE else None


def _agent_ids(path: Path, key: str, sample, sequence: Sequence) -> list[str]:
    ids = field(path, sample, "cav_id_list", key)
    if not isinstance(ids, list) or not ids:
        raise LoaderError(f"{path}: {key}.cav_id_list: expected a non-empty list of agent ids, got {ids!r}")
    ids = [str(i) for i in ids]
    dair = sequence.name.startswith("dair_v2x") or sequence.ego == "vehicle"
    return [DAIR_AGENTS.get(i, i) for i in ids] if dair else ids


def _nth(path: Path, key: str, sample, name: str, index: int):
    values = field(path, sample, name, key)
    if not isinstance(values, list) or len(values) <= index:
        raise LoaderError(f"{path}: {key}.{name}: expected one entry per agent of cav_id_list, got {shown(values)}")
    return values[index]


def _sample_boxes(path: Path, key: str, sample, agents: list[str], left_handed: bool) -> dict[str, DetectedBoxes]:
    """Every agent's boxes of one sample."""
    uncertainties = sample.get("uncertainty_np_list")
    out = {}
    for k, agent in enumerate(agents):
        where = f"{key}.pred_corner3d_np_list[{k}]"
        corners = _array(path, _nth(path, key, sample, "pred_corner3d_np_list", k), where, CORNERS)
        if corners.size and (corners.ndim != 3 or corners.shape[1:] != (8, 3)):
            raise LoaderError(f"{path}: {where}: expected {CORNERS}, got shape {corners.shape}")
        corners = corners.reshape(-1, 8, 3)
        if corners.size and np.abs(corners).max() > MAX_COORDINATE:
            raise LoaderError(f"{path}: {where}: a corner coordinate is {np.abs(corners).max():.3g} m from the agent; "
                              f"expected box corners within {MAX_COORDINATE:.0e} m of its LiDAR")
        if left_handed:
            corners[:, :, 1] *= -1
        uncertainty = np.zeros((len(corners), 0))
        if uncertainties is not None and len(corners):
            where = f"{key}.uncertainty_np_list[{k}]"
            uncertainty = _array(path, _nth(path, key, sample, "uncertainty_np_list", k), where)
            if uncertainty.ndim != 2 or len(uncertainty) != len(corners):
                raise LoaderError(f"{path}: {where}: expected {len(corners)} rows (one per box), "
                                  f"got shape {uncertainty.shape}")
        out[agent] = DetectedBoxes(fit_boxes(corners), uncertainty, _scores(path, key, sample, k, len(corners)))
    return out


def _scores(path: Path, key: str, sample: dict, k: int, count: int) -> np.ndarray | None:
    """Agent ``k``'s ``(N,)`` box scores, or None when the sample has no ``pred_score_np_list``."""
    if sample.get("pred_score_np_list") is None:
        return None
    where = f"{key}.pred_score_np_list[{k}]"
    scores = _array(path, _nth(path, key, sample, "pred_score_np_list", k), where).reshape(-1)
    if len(scores) != count:
        raise LoaderError(f"{path}: {where}: expected {count} scores (one per box), got {len(scores)}")
    return scores


def _array(path: Path, value, where: str, expected: str = "nested lists of numbers") -> np.ndarray:
    try:
        array = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise LoaderError(f"{path}: {where}: expected {expected} ({str(exc).splitlines()[0][:120]})") from exc
    if not np.isfinite(array).all():
        raise LoaderError(f"{path}: {where}: expected finite numbers")
    return array
