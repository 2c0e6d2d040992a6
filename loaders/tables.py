"""Reading and checking tables (CSV, Parquet, Arrow/Feather) for the loaders.

The policy for bad values is the same everywhere and lives here:

- a missing or misnamed column, or a value of the wrong type (text where a number is expected),
  refuses the file with a :class:`LoaderError` naming the file, the column and the first bad row;
- a row with a missing, NaN or infinite value in a column the scene needs is dropped and counted
  (``Sequence.dropped_rows``) and a warning names the file and the first such row; a file where
  every row is dropped is refused.

Row numbers in messages are 1-based data rows (the header is not counted).
"""
from __future__ import annotations

import codecs
import warnings
from pathlib import Path

import polars as pl
import pyarrow.feather
import pyarrow.parquet

from .errors import READ_ERRORS, LoaderError, nonempty_file

NUMERIC = (pl.Float64, pl.Float32, pl.Int64, pl.Int32, pl.Int16, pl.Int8,
           pl.UInt64, pl.UInt32, pl.UInt16, pl.UInt8)


def csv_header(path: Path) -> list[str]:
    """The column names of a CSV file, as written (surrounding spaces stripped)."""
    nonempty_file(path)
    require_text(path)
    try:
        columns = pl.read_csv(path, n_rows=0, infer_schema=False).columns
    except READ_ERRORS as exc:
        raise LoaderError(f"{path}: not a readable CSV file ({_short(exc)})") from exc
    return [c.strip() for c in columns]


def require_text(path: Path, sample: int = 4096) -> None:
    """:class:`LoaderError` when the start of ``path`` is not UTF-8 text (NUL bytes or invalid
    UTF-8): a binary file is named in one line instead of its bytes printed as a header."""
    try:
        with path.open("rb") as file:
            head = file.read(sample)
        codecs.getincrementaldecoder("utf-8")().decode(head, final=False)
        binary = b"\0" in head
    except UnicodeDecodeError:
        binary = True
    except OSError as exc:
        raise LoaderError(f"{path}: cannot read the file ({_short(exc)})") from exc
    if binary:
        raise LoaderError(f"{path}: binary content, not a CSV file; expected UTF-8 text with a header row "
                          "naming the columns")


def read_csv(path: Path, types: dict[str, pl.DataType], optional: tuple[str, ...] = ()) -> pl.DataFrame:
    """The columns ``types`` of a CSV file, cast to their types; columns named in ``optional``
    may be absent. Every cell is read as text first, so a bad value is reported by row."""
    header = csv_header(path)
    require_columns(path, header, [c for c in types if c not in optional])
    wanted = [c for c in types if c in header]
    renames = {raw: raw.strip() for raw in _raw_header(path) if raw.strip() in wanted}
    try:
        raw = (pl.scan_csv(path, infer_schema=False)
               .rename(renames)
               .select(wanted)
               .collect())
    except READ_ERRORS as exc:
        raise LoaderError(f"{path}: not a readable CSV file ({_short(exc)})") from exc
    return cast_columns(path, raw, {c: types[c] for c in wanted})


def read_arrow(path: Path, types: dict[str, pl.DataType], optional: tuple[str, ...] = ()) -> pl.DataFrame:
    """The columns ``types`` of a Parquet or Arrow IPC (Feather) file, cast to their types.
    Read with pyarrow and fully validated first, so corrupt bytes become a clear error."""
    nonempty_file(path)
    try:
        if path.suffix.lower() in (".parquet", ".pq"):
            arrow = pyarrow.parquet.read_table(path)
        else:
            arrow = pyarrow.feather.read_table(path, memory_map=False)
        arrow.validate(full=True)
        frame = pl.from_arrow(arrow)
    except READ_ERRORS as exc:
        raise LoaderError(f"{path}: not a readable {path.suffix} table ({_short(exc)})") from exc
    require_columns(path, frame.columns, [c for c in types if c not in optional])
    wanted = [c for c in types if c in frame.columns]
    return cast_columns(path, frame.select(wanted), {c: types[c] for c in wanted})


def require_columns(path: Path, present: list[str], needed: list[str]) -> None:
    missing = [c for c in needed if c not in present]
    if missing:
        raise LoaderError(f"{path}: missing column(s) {', '.join(missing)}; "
                          f"expected {', '.join(needed)}; found {', '.join(present) or 'none'}")


def cast_columns(path: Path, frame: pl.DataFrame, types: dict[str, pl.DataType]) -> pl.DataFrame:
    """``frame`` with each column cast to its type; a value that does not convert is refused."""
    out = {}
    for name, dtype in types.items():
        column = frame[name]
        if dtype == pl.Utf8:
            converted = None if column.dtype.is_nested() else column.cast(pl.Utf8, strict=False).str.strip_chars()
        elif column.dtype == pl.Utf8:
            converted = column.str.strip_chars().cast(dtype, strict=False)
        elif column.dtype in NUMERIC or column.dtype == pl.Boolean:
            converted = column.cast(dtype, strict=False)
        else:
            converted = None
        if converted is None:
            raise LoaderError(f"{path}: column {name} has type {column.dtype}, expected {_type_name(dtype)}")
        bad = converted.is_null() & column.is_not_null()
        if dtype != pl.Utf8 and column.dtype == pl.Utf8:
            bad = bad & (column.str.strip_chars() != "")
        if dtype.is_integer() and column.dtype.is_float():
            bad = bad | (converted.cast(pl.Float64) != column).fill_null(False)
        if bad.any():
            row = int(bad.arg_max())
            raise LoaderError(f"{path}: row {row + 1}, column {name}: {column[row]!r} is not "
                              f"{_type_name(dtype)}")
        out[name] = converted
    return pl.DataFrame(out)


def drop_unusable(path: Path, frame: pl.DataFrame, columns: list[str]) -> tuple[pl.DataFrame, int]:
    """``frame`` without rows that have a missing, NaN or infinite value in ``columns``, and how
    many were dropped (with a warning naming the first). All rows unusable: refused."""
    usable = pl.all_horizontal(
        [pl.col(c).is_not_null() & (pl.col(c).is_finite() if frame[c].dtype.is_float() else True)
         for c in columns])
    mask = frame.select(usable.alias("ok"))["ok"]
    dropped = int((~mask).sum())
    if dropped == 0:
        return frame, 0
    if dropped == len(frame):
        raise LoaderError(f"{path}: every row has a missing, NaN or infinite value in "
                          f"{', '.join(columns)}")
    first = int((~mask).arg_max())
    warnings.warn(f"{path}: dropped {dropped} row(s) with a missing, NaN or infinite value "
                  f"(first: row {first + 1})", stacklevel=3)
    return frame.filter(mask), dropped


def require_rows(path: Path, frame: pl.DataFrame) -> None:
    if frame.height == 0:
        raise LoaderError(f"{path}: no data rows")


def _raw_header(path: Path) -> list[str]:
    return pl.read_csv(path, n_rows=0, infer_schema=False).columns


def _type_name(dtype: pl.DataType) -> str:
    if dtype == pl.Utf8:
        return "text"
    if dtype.is_integer():
        return "an integer"
    return "a number"


def _short(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0][:200] if text else type(exc).__name__
