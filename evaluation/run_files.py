"""Reading back a run folder's files for ``evaluate.py compare``: ``metrics.json``, ``success_curve.csv``
and which datasets and protocols the run used (``trials.parquet``).

Every file is checked before use: read only when it is a regular file of at most
:data:`MAX_FILE_BYTES` (a FIFO or a huge file never blocks or fills memory), parsed with its
nesting bounded, and its values checked, so that anything a run did not write is reported as
:class:`RunFileError` in one line naming the file and the field.
"""
from __future__ import annotations

import io
import json
import math
from pathlib import Path
from typing import Any

import polars as pl

from loaders.errors import READ_ERRORS

from .presets import NotRegularFile, read_regular

MAX_FILE_BYTES = 16 * 2**20
"""A run's metrics.json and success_curve.csv are a few kilobytes; a larger one is not a run's."""
CURVE_KEYS = ("rte_max_m", "rre_max_deg")
"""The first two columns of ``success_curve.csv``: the thresholds (metres, degrees)."""


class RunFileError(ValueError):
    """A run's file that cannot be read or holds what a run never writes; the message names both."""


def read_bounded(path: Path) -> bytes:
    """The bytes of the regular file ``path`` (opened without blocking: a FIFO is refused, never
    waited on), refused when larger than :data:`MAX_FILE_BYTES`."""
    try:
        data = read_regular(path, MAX_FILE_BYTES)
    except NotRegularFile as error:
        raise RunFileError(f"{path}: {error}") from None
    except OSError as error:
        raise RunFileError(f"{path}: cannot read it ({error.strerror or error})") from None
    if len(data) > MAX_FILE_BYTES:
        raise RunFileError(f"{path}: larger than {MAX_FILE_BYTES // 2**20} MB; not a file evaluate.py wrote")
    return data


def describe(value: Any) -> str:
    """A short name for what ``value`` is, for an error message."""
    if isinstance(value, bool):
        return f"the boolean {str(value).lower()}"
    if isinstance(value, str):
        return f"the text {value[:20]!r}{'…' if len(value) > 20 else ''}"
    if isinstance(value, int):
        return f"an integer of {len(str(abs(value)))} digits, too large for a number"
    if isinstance(value, float):
        return f"{value}, not a finite number"
    return f"a JSON {'object' if isinstance(value, dict) else 'array'}"


def is_metric(value: Any) -> bool:
    """Whether ``value`` is what metrics.json holds: null or a finite number (JSON's NaN counts as null)."""
    if value is None:
        return True
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        number = float(value)
    except OverflowError:
        return False
    return not math.isinf(number)


def load_metrics(path: Path) -> dict[str, dict[str, Any]]:
    """``metrics.json`` at ``path``: an object of methods, each an object of metrics, every metric
    null or a finite number; :class:`RunFileError` naming the file and the field otherwise."""
    data = read_bounded(path)
    try:
        metrics = json.loads(data)
    except RecursionError:
        raise RunFileError(f"{path}: nested too deeply; not a metrics file") from None
    except (UnicodeDecodeError, ValueError) as error:
        raise RunFileError(f"{path}: not readable as JSON ({error})") from None
    if not isinstance(metrics, dict) or not all(isinstance(v, dict) for v in metrics.values()):
        raise RunFileError(f"{path}: not a metrics file (expected an object of methods, each an object of metrics)")
    for method, values in metrics.items():
        for key, value in values.items():
            if not is_metric(value):
                raise RunFileError(f"{path}: {method}.{key} is {describe(value)}; expected a number or null")
    return metrics


def load_curve(path: Path) -> pl.DataFrame | None:
    """``success_curve.csv`` at ``path`` (None when the run has none): the two threshold columns,
    finite, then one numeric success-rate column per method; :class:`RunFileError` otherwise."""
    if not path.exists():
        return None
    data = read_bounded(path)
    if b"\0" in data[:4096]:
        raise RunFileError(f"{path}: binary content, not a success curve (expected CSV text)")
    try:
        data.decode("utf-8")
        curve = pl.read_csv(io.BytesIO(data))
    except READ_ERRORS as error:
        first = str(error).strip().splitlines()[0] if str(error).strip() else type(error).__name__
        raise RunFileError(f"{path}: not a readable CSV file ({first})") from None
    check_curve(path, curve)
    return curve


def check_curve(path: Path, curve: pl.DataFrame) -> None:
    """:class:`RunFileError` unless ``curve`` starts with the threshold columns, has rows, numeric
    columns only and finite thresholds."""
    if tuple(curve.columns[:2]) != CURVE_KEYS:
        raise RunFileError(f"{path}: the first columns are {', '.join(curve.columns[:2]) or 'none'}; "
                           f"expected {', '.join(CURVE_KEYS)}")
    if curve.height == 0:
        raise RunFileError(f"{path}: no rows; expected one row per threshold")
    for name, dtype in curve.schema.items():
        if not dtype.is_numeric():
            raise RunFileError(f"{path}: column {name!r} holds {dtype} values; expected numbers")
    for name in CURVE_KEYS:
        values = curve[name].cast(pl.Float64)
        if values.null_count() or not values.is_finite().all():
            raise RunFileError(f"{path}: column {name!r} has an empty or non-finite threshold")


def provenance(run: Path) -> dict[str, list[str]] | None:
    """The datasets and protocols of the run's trials (``trials.parquet``), or None when it has no
    readable table with those columns (then nothing can be said about them)."""
    path = run / "trials.parquet"
    if not path.is_file():
        return None
    try:
        found = pl.scan_parquet(path).select("dataset", "protocol").unique().collect()
    except READ_ERRORS:
        return None
    return {name: sorted(str(v) for v in found[name].unique().to_list()) for name in ("dataset", "protocol")}
