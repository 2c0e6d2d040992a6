"""The scene model every loader produces: a sequence of frames of world-frame boxes.

Boxes follow the project's conventions: right-handed world frame, metres, radians,
box centre, full sizes. A frame's objects are a polars DataFrame with the canonical columns
:data:`OBJECT_COLUMNS`; ``Frame.boxes()`` gives the ``(N, 7)`` array ``cbm`` takes.

Tables are grouped by frame once, when the sequence is built; a frame is then a pair of row
offsets, and every per-frame accessor is a slice.
"""
from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import polars as pl

from cbm import se2

from .pointcloud import cached_pcd

OBJECT_COLUMNS: dict[str, pl.DataType] = {
    "track_id": pl.Utf8,
    "category": pl.Utf8,
    "x": pl.Float64,
    "y": pl.Float64,
    "z": pl.Float64,
    "length": pl.Float64,
    "width": pl.Float64,
    "height": pl.Float64,
    "yaw": pl.Float64,
}
BOX_COLUMNS = ["x", "y", "z", "length", "width", "height", "yaw"]
SIZED = ["x", "y", "z", "length", "width", "height"]
"""The columns in metres, of objects and agents alike."""
AGENT_COLUMNS: dict[str, pl.DataType] = {
    "agent_id": pl.Utf8,
    "x": pl.Float64,
    "y": pl.Float64,
    "z": pl.Float64,
    "yaw": pl.Float64,
    "length": pl.Float64,
    "width": pl.Float64,
    "height": pl.Float64,
}
VISIBILITY_COLUMNS: dict[str, pl.DataType] = {"agent_id": pl.Utf8, "track_id": pl.Utf8}


@dataclass(frozen=True)
class MapGeometry:
    """Map polylines to draw, in the sequence's world frame.

    ``polylines`` is a list of ``(kind, points)`` with ``points`` an ``(M, 2)`` float array;
    kinds used by the loaders: ``"lane_boundary"``, ``"crossing"``, ``"drivable_area"``
    (closed outlines repeat their first point at the end).
    """

    polylines: list[tuple[str, np.ndarray]] = field(default_factory=list)

    def __iter__(self) -> Iterator[tuple[str, np.ndarray]]:
        return iter(self.polylines)

    def __len__(self) -> int:
        return len(self.polylines)

    def kinds(self) -> list[str]:
        """The distinct kinds, in order of first appearance."""
        return list(dict.fromkeys(kind for kind, _ in self.polylines))

    def of_kind(self, kind: str) -> list[np.ndarray]:
        """The polylines of one kind."""
        return [points for k, points in self.polylines if k == kind]

    def bounds(self) -> tuple[np.ndarray, np.ndarray] | None:
        """``(min_xy, max_xy)`` over all points, or ``None`` for an empty map."""
        if not self.polylines:
            return None
        points = np.concatenate([p for _, p in self.polylines])
        return points.min(axis=0), points.max(axis=0)


def _frame_offsets(frame_column: np.ndarray, n_frames: int) -> np.ndarray:
    """Row offsets of each frame in a table sorted by frame index: rows of frame k are
    ``offsets[k]:offsets[k + 1]``."""
    return np.searchsorted(frame_column, np.arange(n_frames + 1), side="left")


def _grouped(table: pl.DataFrame, columns: dict[str, pl.DataType], n_frames: int,
             by: list[str]) -> tuple[pl.DataFrame, np.ndarray]:
    """``table`` (with an integer ``frame`` column) sorted by frame (stable) and restricted to
    ``columns`` with their canonical types, plus its frame offsets."""
    table = table.sort(["frame", *by], maintain_order=True)
    offsets = _frame_offsets(table["frame"].to_numpy(), n_frames)
    return table.select([pl.col(name).cast(dtype) for name, dtype in columns.items()]), offsets


class Sequence:
    """A loaded dataset: frames of objects in one world frame, with optional agents, per-agent
    visibility and map.

    Build it from long tables that carry an integer ``frame`` column (0-based frame index):
    ``objects`` with :data:`OBJECT_COLUMNS`, ``agents`` with :data:`AGENT_COLUMNS`,
    ``visibility`` with ``agent_id, track_id`` (one row per object an agent sees).
    ``ego`` names the agent the dataset itself treats as the ego (e.g. Argoverse's recording car,
    OpenCOOD's ego CAV), if any. ``dropped_rows`` counts input rows skipped for missing, NaN or
    infinite values.

    Optional, for releases of several scenarios (OPV2V split roots): ``scenarios`` maps each
    scenario's name to its first frame index (in frame order); ``frame_egos`` the ego of each
    frame when it changes with the scenario; ``predicted_poses`` maps ``(frame index, agent id)``
    to the dataset's own noisy ``(x, y, yaw)`` of that agent (OPV2V ``predicted_ego_pos``).
    ``warnings`` lists what the loader skipped (gaps), ``notes`` how it read what the release leaves
    open (a calibration fallback, an association derived by distance): both for the app and the CLI to show.
    """

    def __init__(
        self,
        name: str,
        objects: pl.DataFrame,
        frame_ids: list,
        timestamps: np.ndarray,
        agents: pl.DataFrame | None = None,
        visibility: pl.DataFrame | None = None,
        map: MapGeometry | None = None,
        ego: str | None = None,
        dropped_rows: int = 0,
        scenarios: dict[str, int] | None = None,
        frame_egos: list[str] | None = None,
        predicted_poses: dict[tuple[int, str], tuple[float, float, float]] | None = None,
        warnings: list[str] | None = None,
        notes: list[str] | None = None,
    ) -> None:
        self.name = name
        self.ego = ego
        self.scenarios = dict(scenarios) if scenarios else None
        self.frame_egos = list(frame_egos) if frame_egos is not None else None
        self.predicted_poses = dict(predicted_poses or {})
        self.warnings = list(warnings or [])
        self.notes = list(notes or [])
        self.frame_ids = list(frame_ids)
        self.timestamps = np.asarray(timestamps, dtype=np.float64)
        if len(self.timestamps) != len(self.frame_ids):
            raise ValueError("frame_ids and timestamps differ in length")
        self.map = map
        self.dropped_rows = int(dropped_rows)
        self.point_clouds: dict[tuple[int, str], tuple[Path, bool]] = {}
        """``(frame index, agent id) -> (PCD file, left-handed)`` for the datasets that ship LiDAR
        points (read on demand by ``Frame.points``; left-handed files have y mirrored on read)."""
        self.agent_views: dict[tuple[int, str], tuple[np.ndarray, np.ndarray]] = {}
        """``(frame index, agent id) -> (track ids, (N, 7) world boxes)``: each object as that agent's own
        labels give it, mapped to the world with the dataset's pose of that agent (DAIR-V2X-C,
        the OPV2V family); ``objects`` keeps one box per object. What the dataset-calibration check
        compares (``evaluation.calibration_check``)."""
        self.left_out_of_trials: frozenset[str] = frozenset()
        """Categories of ``objects`` that trials leave out unless the user includes them (set it to an
        empty set): the OPV2V family's pedestrians (``walkers``), which the release's vehicle-only
        benchmarks never match."""
        self.agent_times: dict[int, dict[str, float]] = {}
        """``frame index -> agent id -> seconds``: when that agent captured its part of the frame, on
        the clock of ``timestamps``, where the dataset keeps each agent's own time (DAIR-V2X's vehicle
        and infrastructure frames, the OPV2V family's per-CAV files); a late message starts from it."""
        self.tracked = True
        """Whether a track id names the same object in every frame (DAIR-V2X-C's pairs are samples whose
        ids are label indices: False); a late message follows its objects back only where it does."""
        self.detections: dict[int, dict] = {}
        """``frame index -> agent id -> loaders.detections.DetectedBoxes``: a real detector's boxes,
        when a detections file is attached (``loaders.open(path, detections=...)``)."""
        n = len(self.frame_ids)
        self.objects, self._object_offsets = _grouped(objects, OBJECT_COLUMNS, n, [])
        self._boxes = self.objects.select(BOX_COLUMNS).to_numpy().astype(np.float64, copy=False)
        self._track_ids = self.objects["track_id"].to_numpy().astype(str)
        self._categories = self.objects["category"].to_numpy().astype(str)
        self.agents = None
        if agents is not None:
            self.agents, self._agent_offsets = _grouped(agents, AGENT_COLUMNS, n, [])
            self._agent_ids = self.agents["agent_id"].to_numpy().astype(str)
        self.visibility = None
        if visibility is not None:
            self.visibility, self._visibility_offsets = _grouped(
                visibility, VISIBILITY_COLUMNS, n, ["agent_id"])
            self._seen_by = self.visibility["agent_id"].to_numpy().astype(str)
            self._seen_tracks = self.visibility["track_id"].to_numpy().astype(str)

    def __len__(self) -> int:
        return len(self.frame_ids)

    def beyond(self, limit: float) -> str | None:
        """Where the first object or agent position or size larger than ``limit`` metres in size is
        ("frame F, object T: x = V"), or None when every one is within it."""
        tables = (("object", self.objects, "track_id", self._object_offsets),
                  ("agent", self.agents, "agent_id", getattr(self, "_agent_offsets", None)))
        for kind, table, key, offsets in tables:
            if table is None or table.is_empty():
                continue
            rows, columns = np.nonzero(np.abs(table.select(SIZED).to_numpy()) > limit)
            if len(rows):
                row, name = int(rows[0]), SIZED[columns[0]]
                frame = self.frame_ids[int(np.searchsorted(offsets, row, side="right")) - 1]
                return f"frame {frame}, {kind} {table[key][row]}: {name} = {table[name][row]:g}"
        return None

    def __getitem__(self, index: int) -> Frame:
        n = len(self)
        if not -n <= index < n:
            raise IndexError(f"frame index {index} out of range for {n} frames")
        return Frame(self, index % n)

    def __iter__(self) -> Iterator[Frame]:
        return (Frame(self, k) for k in range(len(self)))

    def __repr__(self) -> str:
        return (f"Sequence({self.name!r}, {len(self)} frames, {len(self.objects)} boxes, "
                f"agents={self.agents is not None}, map={self.map is not None})")


class Frame:
    """One frame of a :class:`Sequence`: views into the sequence's grouped tables."""

    __slots__ = ("sequence", "index")

    def __init__(self, sequence: Sequence, index: int) -> None:
        self.sequence = sequence
        self.index = index

    @property
    def frame_id(self):
        return self.sequence.frame_ids[self.index]

    @property
    def timestamp(self) -> float:
        """Seconds."""
        return float(self.sequence.timestamps[self.index])

    @property
    def scenario(self) -> str | None:
        """The name of the scenario this frame belongs to, or ``None`` when the dataset names none."""
        starts = self.sequence.scenarios
        if not starts:
            return None
        return max(((k, name) for name, k in starts.items() if k <= self.index), default=(0, None))[1]

    @property
    def ego(self) -> str | None:
        """The dataset's ego in this frame (``Sequence.frame_egos``, else ``Sequence.ego``)."""
        egos = self.sequence.frame_egos
        return egos[self.index] if egos is not None else self.sequence.ego

    def predicted_pose(self, agent_id: str) -> np.ndarray | None:
        """``(3, 3)`` SE(2) pose the dataset itself reports for the agent (its localization, with
        its error), or ``None`` when the dataset gives none."""
        pose = self.sequence.predicted_poses.get((self.index, str(agent_id)))
        return None if pose is None else se2.make(*pose)

    def _rows(self, offsets: np.ndarray) -> slice:
        return slice(int(offsets[self.index]), int(offsets[self.index + 1]))

    @property
    def objects(self) -> pl.DataFrame:
        """The frame's objects with the canonical columns (:data:`OBJECT_COLUMNS`)."""
        rows = self._rows(self.sequence._object_offsets)
        return self.sequence.objects.slice(rows.start, rows.stop - rows.start)

    def boxes(self) -> np.ndarray:
        """``(N, 7)`` float64 ``x, y, z, length, width, height, yaw``, rows as in :attr:`objects`
        (a fresh copy: safe to modify)."""
        return self.sequence._boxes[self._rows(self.sequence._object_offsets)].copy()

    @property
    def track_ids(self) -> np.ndarray:
        return self.sequence._track_ids[self._rows(self.sequence._object_offsets)]

    @property
    def categories(self) -> np.ndarray:
        return self.sequence._categories[self._rows(self.sequence._object_offsets)]

    def __len__(self) -> int:
        rows = self._rows(self.sequence._object_offsets)
        return rows.stop - rows.start

    @property
    def agents(self) -> pl.DataFrame | None:
        """The agents present (:data:`AGENT_COLUMNS`), or ``None`` if the dataset has none."""
        seq = self.sequence
        if seq.agents is None:
            return None
        rows = self._rows(seq._agent_offsets)
        return seq.agents.slice(rows.start, rows.stop - rows.start)

    @property
    def visibility(self) -> dict[str, np.ndarray] | None:
        """``agent_id -> track ids that agent sees``, or ``None`` if the dataset does not say.
        Agents present in the frame that see nothing map to an empty array."""
        seq = self.sequence
        if seq.visibility is None:
            return None
        rows = self._rows(seq._visibility_offsets)
        agents, tracks = seq._seen_by[rows], seq._seen_tracks[rows]
        starts = np.flatnonzero(np.r_[True, agents[1:] != agents[:-1]]) if len(agents) else []
        bounds = [*starts, len(agents)]
        seen = {str(agents[a]): tracks[a:b] for a, b in zip(bounds[:-1], bounds[1:])}
        present = seq._agent_ids[self._rows(seq._agent_offsets)] if seq.agents is not None else []
        return {**{str(a): tracks[:0] for a in present}, **seen}

    def agent_times(self) -> dict[str, float]:
        """``agent id -> seconds``: each agent's own capture time of this frame (``Sequence.agent_times``),
        empty where the dataset has one time per frame."""
        return dict(self.sequence.agent_times.get(self.index, {}))

    @property
    def detections(self) -> dict | None:
        """``agent id -> DetectedBoxes`` (each agent's detected boxes in its own frame), or ``None``
        when no detections file gives this frame any."""
        return self.sequence.detections.get(self.index)

    def agent_view(self, agent_id: str) -> tuple[np.ndarray, np.ndarray] | None:
        """``(track ids, (N, 7) world boxes)`` of the objects as this agent's own labels give them
        (``Sequence.agent_views``), or ``None`` when the dataset keeps no per-agent labels."""
        return self.sequence.agent_views.get((self.index, str(agent_id)))

    def points(self, agent_id: str) -> np.ndarray | None:
        """``(N, 3)`` float32 LiDAR points of an agent in its own sensor frame (right-handed), or
        ``None`` when the dataset has none for this agent and frame."""
        source = self.sequence.point_clouds.get((self.index, str(agent_id)))
        if source is None:
            return None
        points = cached_pcd(source[0]).copy()
        if source[1]:
            points[:, 1] *= -1
        return points

    def agent_pose(self, agent_id: str) -> np.ndarray:
        """``(3, 3)`` SE(2) pose of an agent in the world frame (maps agent-frame points to world)."""
        seq = self.sequence
        if seq.agents is None:
            raise KeyError(f"{seq.name}: the dataset has no agents")
        rows = self._rows(seq._agent_offsets)
        hits = np.flatnonzero(seq._agent_ids[rows] == str(agent_id))
        if not len(hits):
            present = ", ".join(seq._agent_ids[rows]) or "none"
            raise KeyError(f"{seq.name} frame {self.index}: no agent {agent_id!r} (present: {present})")
        row = rows.start + int(hits[0])
        x, y, yaw = (seq.agents[name][row] for name in ("x", "y", "yaw"))
        return se2.make(x, y, yaw)

    def __repr__(self) -> str:
        return f"Frame({self.sequence.name!r}, index={self.index}, frame_id={self.frame_id!r}, {len(self)} objects)"
