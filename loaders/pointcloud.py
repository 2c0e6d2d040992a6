"""LiDAR point clouds: PCD files (the Point Cloud Library's format, version 0.7) read with pypcd4.

A PCD file is a text header (``FIELDS``, ``SIZE``, ``TYPE``, ``COUNT``, ``WIDTH``, ``POINTS``, then
``DATA ascii|binary|binary_compressed``) followed by the points: one text line per point, packed
records, or LZF-compressed columns (what PCL writes and DAIR-V2X ships). pypcd4 (BSD-3-Clause)
parses all three and any field list (``x y z``, Open3D's ``x y z rgb``, DAIR-V2X's ``x y z
intensity``); only ``x, y, z`` are kept, rows with a non-finite coordinate dropped. What pypcd4
cannot read -- a header without the keys above, a truncated or corrupt body, a Git LFS pointer in
place of the file -- is a one-line :class:`LoaderError` naming the file.
"""
from __future__ import annotations

import struct
from functools import lru_cache
from pathlib import Path

import numpy as np

from .errors import READ_ERRORS, LoaderError, nonempty_file, shown

HEADER_KEYS = ("FIELDS", "SIZE", "TYPE", "COUNT", "WIDTH", "POINTS", "DATA")
PCD_ERRORS = (*READ_ERRORS, RuntimeError, struct.error, KeyError, IndexError)
"""What pypcd4 (numpy, lzf, struct underneath) raises on a malformed body."""


def read_pcd(path: Path) -> np.ndarray:
    """``(N, 3)`` float32 ``x, y, z`` of a PCD file, in the file's own (sensor) frame."""
    nonempty_file(path)
    cloud = _parsed(path)
    fields = cloud.metadata.fields
    if not {"x", "y", "z"} <= set(fields):
        raise LoaderError(f"{path}: PCD header FIELDS: expected x, y and z, got {' '.join(fields)!r}")
    records = np.atleast_1d(cloud.pc_data)
    expected, kind = cloud.metadata.points, cloud.metadata.data.value
    if len(records) != expected:
        raise LoaderError(f"{path}: DATA {kind}: expected {expected} points, got {len(records)}")
    xyz = np.stack([records[name].astype(np.float32) for name in ("x", "y", "z")], axis=1)
    return xyz[np.isfinite(xyz).all(axis=1)]


def _parsed(path: Path):
    """The file parsed by pypcd4 (a ``pypcd4.PointCloud``), its failures turned into a
    :class:`LoaderError`. pypcd4 (with pydantic) is imported on the first sweep read: it adds about
    half a second to ``import loaders``, which most sessions never need."""
    import pypcd4

    try:
        return pypcd4.PointCloud.from_path(path)
    except PCD_ERRORS as exc:
        if callable(getattr(exc, "errors", None)):
            raise LoaderError(f"{path}: PCD header: {_header_problem(exc)}") from exc
        raise LoaderError(f"{path}: {_body_problem(path, exc)}") from exc


def _header_problem(exc) -> str:
    """What is wrong with a header (pypcd4's pydantic ``ValidationError``, a ``ValueError``), in its
    own keys (``missing SIZE, TYPE``)."""
    missing = [str(error["loc"][0]).upper() for error in exc.errors()
               if error["type"] in ("missing", "value_error.missing")]
    if missing:
        return f"missing {', '.join(missing)} (expected {', '.join(HEADER_KEYS)})"
    error = exc.errors()[0]
    return f"{str(error['loc'][0]).upper()}: {error['msg']} (got {shown(error.get('input'))})"


def _body_problem(path: Path, exc: BaseException) -> str:
    """A header that parses but whose points do not: which ``DATA`` and how many were expected."""
    header = _header_lines(path)
    points, data = header.get("POINTS", "?"), header.get("DATA", "?")
    first = str(exc).strip().splitlines()
    detail = first[0][:200] if first else type(exc).__name__
    return f"DATA {data}: expected {points} points of FIELDS {header.get('FIELDS', '?')}, cannot read them ({detail})"


def _header_lines(path: Path) -> dict[str, str]:
    """The header's ``KEY values`` up to ``DATA`` (for messages only)."""
    header: dict[str, str] = {}
    with path.open("rb") as file:
        for raw in file:
            line = raw.decode("ascii", "replace").strip()
            if not line or line.startswith("#"):
                continue
            key, _, values = line.partition(" ")
            header[key.upper()] = values.strip()
            if key.upper() == "DATA" or len(header) > 20:
                break
    return header


@lru_cache(maxsize=8)
def cached_pcd(path: Path) -> np.ndarray:
    """:func:`read_pcd` remembered for the last few files (a redraw reads the same sweeps again);
    the array is shared: copy it before changing it."""
    points = read_pcd(path)
    points.flags.writeable = False
    return points
