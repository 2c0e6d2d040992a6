"""The one exception every loader raises for input it cannot read."""
from __future__ import annotations

from pathlib import Path

import polars as pl
import pyarrow as pa


class LoaderError(ValueError):
    """A dataset file or folder that cannot be read; the message names the file, the row or key
    where it can, and what was expected."""


READ_ERRORS = (
    pl.exceptions.PolarsError,
    pl.exceptions.PanicException,
    pa.ArrowException,
    OSError,
    UnicodeDecodeError,
    ValueError,
    TypeError,
    OverflowError,
)
"""What third-party readers (polars, pyarrow, json, yaml) raise on malformed bytes."""


def existing_path(path: str | Path, what: str = "dataset path") -> Path:
    """``path`` made absolute, with ``~`` expanded, after checking that it exists."""
    try:
        resolved = Path(path).expanduser().resolve()
    except (OSError, RuntimeError, TypeError, ValueError) as exc:
        raise LoaderError(f"{what} {path!r}: cannot resolve it ({exc})") from exc
    if not resolved.exists():
        raise LoaderError(f"{what} {str(resolved)!r} does not exist")
    return resolved


def nonempty_file(path: Path) -> Path:
    """``path`` after checking that it is a file with at least one byte."""
    if not path.is_file():
        raise LoaderError(f"{path}: expected a file")
    if path.stat().st_size == 0:
        raise LoaderError(f"{path}: the file is empty")
    return path
