"""LiDAR point clouds: PCD files (ASCII and binary, as OPV2V / V2XSet ship them) read with numpy.

A PCD file is a text header (``FIELDS``, ``SIZE``, ``TYPE``, ``COUNT``, ``POINTS``, then ``DATA
ascii|binary``) followed by the points (the Point Cloud Library's file format, version 0.7). Only
``x, y, z`` are kept. ``binary_compressed`` (LZF) is refused with a clear message.
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from .errors import READ_ERRORS, LoaderError, nonempty_file

HEADER_KEYS = ("FIELDS", "SIZE", "TYPE", "COUNT", "POINTS", "DATA")
NUMPY_TYPES = {("F", 4): "<f4", ("F", 8): "<f8", ("I", 1): "<i1", ("I", 2): "<i2", ("I", 4): "<i4",
               ("I", 8): "<i8", ("U", 1): "<u1", ("U", 2): "<u2", ("U", 4): "<u4", ("U", 8): "<u8"}


def read_pcd(path: Path) -> np.ndarray:
    """``(N, 3)`` float32 ``x, y, z`` of a PCD file, in the file's own (sensor) frame."""
    data = nonempty_file(path).read_bytes()
    header, body = _split_header(path, data)
    dtype = _record_type(path, header)
    count = _integer(path, header, "POINTS")
    kind = header["DATA"][0].lower()
    if kind == "ascii":
        records = _ascii_records(path, body, dtype, count)
    elif kind == "binary":
        if len(body) < count * dtype.itemsize:
            raise LoaderError(f"{path}: DATA binary: expected {count} points of {dtype.itemsize} bytes, "
                              f"got {len(body)} bytes")
        records = np.frombuffer(body, dtype=dtype, count=count)
    else:
        raise LoaderError(f"{path}: DATA: expected ascii or binary, got {header['DATA'][0]!r}")
    xyz = np.stack([records[name].astype(np.float32) for name in ("x", "y", "z")], axis=1)
    return xyz[np.isfinite(xyz).all(axis=1)]


def _split_header(path: Path, data: bytes) -> tuple[dict[str, list[str]], bytes]:
    """The header's ``KEY values`` lines by key, and the bytes after the ``DATA`` line."""
    header: dict[str, list[str]] = {}
    offset = 0
    while offset < len(data):
        end = data.find(b"\n", offset)
        end = len(data) if end < 0 else end
        try:
            line = data[offset:end].decode("ascii").strip()
        except UnicodeDecodeError as exc:
            raise LoaderError(f"{path}: header line is not text ({exc})") from exc
        offset = end + 1
        if not line or line.startswith("#"):
            continue
        key, *values = line.split()
        header[key.upper()] = values
        if key.upper() == "DATA":
            break
    missing = [key for key in HEADER_KEYS if key not in header]
    if missing:
        raise LoaderError(f"{path}: PCD header: missing {', '.join(missing)} (expected {', '.join(HEADER_KEYS)})")
    return header, data[offset:]


def _integer(path: Path, header: dict[str, list[str]], key: str) -> int:
    values = header[key]
    if len(values) != 1 or not values[0].isdigit():
        raise LoaderError(f"{path}: PCD header {key}: expected one non-negative integer, got {' '.join(values)!r}")
    return int(values[0])


def _record_type(path: Path, header: dict[str, list[str]]) -> np.dtype:
    """The numpy record type of one point from ``FIELDS``, ``SIZE``, ``TYPE`` and ``COUNT``."""
    fields, sizes, types, counts = (header[key] for key in ("FIELDS", "SIZE", "TYPE", "COUNT"))
    if not len(fields) == len(sizes) == len(types) == len(counts):
        raise LoaderError(f"{path}: PCD header: FIELDS, SIZE, TYPE and COUNT differ in length")
    if not {"x", "y", "z"} <= set(fields):
        raise LoaderError(f"{path}: PCD header FIELDS: expected x, y and z, got {' '.join(fields)!r}")
    columns = []
    for k, (name, size, kind, count) in enumerate(zip(fields, sizes, types, counts)):
        key = (kind.upper(), int(size) if size.isdigit() else -1)
        if key not in NUMPY_TYPES or not count.isdigit() or int(count) < 1:
            raise LoaderError(f"{path}: PCD header field {name!r}: unsupported TYPE {kind} SIZE {size} COUNT {count}")
        shape = () if int(count) == 1 else (int(count),)
        columns.append((name if name != "_" else f"_pad{k}", NUMPY_TYPES[key], shape))
    return np.dtype(columns)


def _ascii_records(path: Path, body: bytes, dtype: np.dtype, count: int) -> np.ndarray:
    """``count`` points of an ASCII body, one point a line, values separated by spaces."""
    width = sum(int(np.prod(dtype[name].shape)) or 1 for name in dtype.names)
    try:
        values = np.array(body.split(), dtype=np.float64)
    except READ_ERRORS as exc:
        raise LoaderError(f"{path}: DATA ascii: expected numbers ({exc})") from exc
    if len(values) < count * width:
        raise LoaderError(f"{path}: DATA ascii: expected {count} points of {width} values, got {len(values)} values")
    table = values[: count * width].reshape(count, width)
    records = np.zeros(count, dtype=dtype)
    column = 0
    for name in dtype.names:
        size = int(np.prod(dtype[name].shape)) or 1
        records[name] = table[:, column] if size == 1 else table[:, column:column + size]
        column += size
    return records


@lru_cache(maxsize=8)
def cached_pcd(path: Path) -> np.ndarray:
    """:func:`read_pcd` remembered for the last few files (a redraw reads the same sweeps again);
    the array is shared: copy it before changing it."""
    points = read_pcd(path)
    points.flags.writeable = False
    return points
