"""INTERACTION dataset track files (``recorded_trackfiles/<scenario>/``).

``vehicle_tracks_NNN.csv`` (:data:`VEHICLE_COLUMNS`) and ``pedestrian_tracks_NNN.csv``
(:data:`PEDESTRIAN_COLUMNS`, points) of one recording number NNN. Open one of the files (its
partner of the same number is read too) or a folder holding one recording number. World frame:
the scenario map's frame (metres); ``psi_rad`` counter-clockwise is the yaw; frames are the
files' ``frame_id`` (10 Hz), timestamps ``timestamp_ms / 1000``. No heights in the data: a typical
height per class; pedestrians (and bicycles in the pedestrian file) get a 0.6 x 0.6 m
footprint and a yaw along their velocity (see :mod:`loaders.tracks`).
"""
from __future__ import annotations

import re
from pathlib import Path

import polars as pl

from .errors import LoaderError
from .scene import Sequence
from .tables import drop_unusable, read_csv, require_rows
from .tracks import indexed_frames, pedestrian_boxes, with_heights

VEHICLE_COLUMNS = ["track_id", "frame_id", "timestamp_ms", "agent_type", "x", "y", "vx", "vy",
                   "psi_rad", "length", "width"]
PEDESTRIAN_COLUMNS = VEHICLE_COLUMNS[:8]
TRACK_FILE = re.compile(r"^(vehicle|pedestrian)_tracks_(\d+)\.csv$")
COMMON = {"track_id": pl.Utf8, "frame_id": pl.Int64, "timestamp_ms": pl.Float64,
          "agent_type": pl.Utf8, "x": pl.Float64, "y": pl.Float64}
EXPECTED = "an INTERACTION track file (vehicle_tracks_*.csv)"


def recognises(path: Path) -> bool:
    if path.is_file():
        return bool(TRACK_FILE.match(path.name))
    return any(TRACK_FILE.match(p.name) for p in path.iterdir() if p.is_file())


def load(path: str | Path) -> Sequence:
    """Load one INTERACTION recording (a track file, or a folder with one recording number)."""
    path = Path(path)
    folder = path.parent if path.is_file() else path
    if path.is_file():
        number = TRACK_FILE.match(path.name)[2]
    else:
        numbers = sorted({m[2] for p in folder.iterdir() if (m := TRACK_FILE.match(p.name))})
        if len(numbers) != 1:
            raise LoaderError(f"{folder}: holds track files of {len(numbers)} recordings "
                              f"({', '.join(numbers) or 'none'}); open one of the files")
        number = numbers[0]
    parts, dropped = [], 0
    vehicles, pedestrians = (folder / f"vehicle_tracks_{number}.csv", folder / f"pedestrian_tracks_{number}.csv")
    if vehicles.is_file():
        types = {**COMMON, "psi_rad": pl.Float64, "length": pl.Float64, "width": pl.Float64}
        boxes, lost = drop_unusable(vehicles, read_csv(vehicles, types), list(types))
        require_rows(vehicles, boxes)
        parts.append(boxes.rename({"psi_rad": "yaw"}))
        dropped += lost
    if pedestrians.is_file():
        types = {**COMMON, "vx": pl.Float64, "vy": pl.Float64}
        points, lost = drop_unusable(pedestrians, read_csv(pedestrians, types), list(types))
        require_rows(pedestrians, points)
        parts.append(pedestrian_boxes(points).drop("vx", "vy"))
        dropped += lost
    objects, frame_ids, timestamps = indexed_frames(parts)
    return Sequence(
        name=f"interaction/{folder.name}/{number}",
        objects=with_heights(objects.rename({"agent_type": "category"})),
        frame_ids=[int(f) for f in frame_ids],
        timestamps=timestamps,
        dropped_rows=dropped,
    )
