"""SinD recordings (drone dataset at a signalised intersection; Xu et al., ITSC 2022).

A recording folder holds ``Veh_smoothed_tracks.csv`` and/or ``Ped_smoothed_tracks.csv``, and meta
files; open the folder or one of the track files. The world frame is the intersection's frame
of the recording (metres); frames are the files' ``frame_id`` values (9.99 Hz), timestamps
``timestamp_ms / 1000``.

- Vehicles: the header must be exactly the official 18 columns (:data:`VEHICLE_COLUMNS`, the
  order the official reader checks). Box centre ``x, y``; ``yaw_rad`` (box axis) is the yaw,
  not ``heading_rad`` (the velocity direction); ``length``, ``width`` as given; no height in the
  data, so a typical height per class (see :mod:`loaders.tracks`).
- Pedestrians (:data:`PEDESTRIAN_COLUMNS`) are points: they get a 0.6 x 0.6 m footprint and a
  yaw along their velocity (0 when standing).
- ``Veh_tracks_meta.csv`` / ``Ped_tracks_meta.csv``, when present, give each track's class (their
  labels can carry a trailing space, stripped here; columns are read by name, since the vehicle
  meta puts width before length); the class replaces the per-row ``agent_type``.
  ``recording_metas.csv`` names the scene (city and recording id). Traffic lights are not part of
  the scene model and are not read (their headers differ per city).
"""
from __future__ import annotations

import warnings
from pathlib import Path

import polars as pl

from .errors import LfsPointer, LoaderError, is_lfs_pointer
from .scene import Sequence
from .tables import csv_header, drop_unusable, read_csv, require_rows
from .tracks import indexed_frames, pedestrian_boxes, with_heights

VEHICLE_FILE = "Veh_smoothed_tracks.csv"
PEDESTRIAN_FILE = "Ped_smoothed_tracks.csv"
VEHICLE_COLUMNS = ["track_id", "frame_id", "timestamp_ms", "agent_type", "x", "y", "vx", "vy",
                   "yaw_rad", "heading_rad", "length", "width", "ax", "ay", "v_lon", "v_lat",
                   "a_lon", "a_lat"]
PEDESTRIAN_COLUMNS = ["track_id", "frame_id", "timestamp_ms", "agent_type", "x", "y", "vx", "vy",
                      "ax", "ay"]
META_FILES = {VEHICLE_FILE: "Veh_tracks_meta.csv", PEDESTRIAN_FILE: "Ped_tracks_meta.csv"}
COMMON = {"track_id": pl.Utf8, "frame_id": pl.Int64, "timestamp_ms": pl.Float64,
          "agent_type": pl.Utf8, "x": pl.Float64, "y": pl.Float64}
EXPECTED = "a SinD recording (Veh_smoothed_tracks.csv / Ped_smoothed_tracks.csv)"


def recognises(path: Path) -> bool:
    """A SinD track file, or a folder with SinD track or meta files."""
    if path.is_file():
        return path.name in (VEHICLE_FILE, PEDESTRIAN_FILE)
    names = (VEHICLE_FILE, PEDESTRIAN_FILE, *META_FILES.values(), "recording_metas.csv")
    return any((path / name).is_file() for name in names)


def load(path: str | Path) -> Sequence:
    """Load a SinD recording folder (or one of its track files)."""
    path = Path(path)
    folder = path.parent if path.is_file() else path
    parts, dropped, pointers = [], 0, []
    for name, reader in ((VEHICLE_FILE, _vehicles), (PEDESTRIAN_FILE, _pedestrians)):
        if (folder / name).is_file():
            try:
                boxes, lost = reader(folder / name)
                parts.append(_with_meta_classes(boxes, folder / META_FILES[name], pointers))
            except LfsPointer as exc:
                pointers.append(exc)
                continue
            dropped += lost
    if not parts:
        if pointers:
            raise pointers[0]
        raise LoaderError(f"{folder}: no SinD track file; expected {VEHICLE_FILE} or {PEDESTRIAN_FILE}")
    objects, frame_ids, timestamps = indexed_frames(parts)
    return Sequence(
        name=_name(folder),
        objects=with_heights(objects.rename({"agent_type": "category"})),
        frame_ids=[int(f) for f in frame_ids],
        timestamps=timestamps,
        dropped_rows=dropped,
        warnings=_skipped_pointers(pointers),
    )


def _skipped_pointers(pointers: list[LfsPointer]) -> list[str]:
    """One warning naming the Git LFS pointer files skipped (also raised as a ``UserWarning``)."""
    if not pointers:
        return []
    note = (f"skipped {len(pointers)} Git LFS pointer file(s), not the data: "
            f"{', '.join(str(p.path) for p in pointers)}; run `git lfs pull` in the dataset's repository")
    warnings.warn(note, UserWarning, stacklevel=3)
    return [note]


def _exact_header(path: Path, expected: list[str]) -> None:
    header = csv_header(path)
    if header != expected:
        at = next((i for i, (a, b) in enumerate(zip(header, expected)) if a != b), min(len(header), len(expected)))
        found = header[at] if at < len(header) else "end of header"
        wanted = expected[at] if at < len(expected) else "end of header"
        raise LoaderError(f"{path}: header column {at + 1} is {found!r}, expected {wanted!r} "
                          f"(the official header is: {', '.join(expected)})")


def _vehicles(path: Path) -> tuple[pl.DataFrame, int]:
    _exact_header(path, VEHICLE_COLUMNS)
    types = {**COMMON, "yaw_rad": pl.Float64, "length": pl.Float64, "width": pl.Float64}
    boxes, dropped = drop_unusable(path, read_csv(path, types), list(types))
    require_rows(path, boxes)
    return boxes.rename({"yaw_rad": "yaw"}), dropped


def _pedestrians(path: Path) -> tuple[pl.DataFrame, int]:
    _exact_header(path, PEDESTRIAN_COLUMNS)
    types = {**COMMON, "vx": pl.Float64, "vy": pl.Float64}
    points, dropped = drop_unusable(path, read_csv(path, types), list(types))
    require_rows(path, points)
    return pedestrian_boxes(points).drop("vx", "vy"), dropped


def _with_meta_classes(boxes: pl.DataFrame, meta: Path, pointers: list[LfsPointer]) -> pl.DataFrame:
    """Replace ``agent_type`` by the meta file's class of each track, where it has one (a meta
    file that is a Git LFS pointer is added to ``pointers`` and not used)."""
    if not meta.is_file():
        return boxes
    try:
        table = read_csv(meta, {"trackId": pl.Utf8, "class": pl.Utf8})
    except LfsPointer as exc:
        pointers.append(exc)
        return boxes
    classes = (table
               .drop_nulls().unique("trackId", keep="first")
               .rename({"trackId": "track_id", "class": "meta_class"}))
    return (boxes.join(classes, on="track_id", how="left", maintain_order="left")
            .with_columns(pl.coalesce("meta_class", "agent_type").alias("agent_type"))
            .drop("meta_class"))


def _name(folder: Path) -> str:
    meta = folder / "recording_metas.csv"
    if meta.is_file() and not is_lfs_pointer(meta):
        info = read_csv(meta, {"RecordingID": pl.Utf8, "City": pl.Utf8})
        if info.height:
            return f"sind/{info['City'][0]} recording {info['RecordingID'][0]}"
    return f"sind/{folder.name}"
