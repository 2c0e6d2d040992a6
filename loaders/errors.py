"""The one exception every loader raises for input it cannot read."""
from __future__ import annotations

import os
import reprlib
import stat
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


SHOWN_CHARS = 80
"""Longest value a message quotes: a 2 KB YAML file of nested aliases stands for a value whose
full repr is half a gigabyte (issue 50, item 3)."""
_SHORT = reprlib.Repr()
_SHORT.maxlevel, _SHORT.maxstring, _SHORT.maxother, _SHORT.maxlong = 2, SHOWN_CHARS, SHOWN_CHARS, 40
_SHORT.maxlist = _SHORT.maxtuple = _SHORT.maxdict = _SHORT.maxset = _SHORT.maxarray = 4


def shown(value: object, limit: int = SHOWN_CHARS) -> str:
    """``value`` as a message quotes it: its repr with nested and long parts cut (``...``), built
    without writing the whole, and at most ``limit`` characters."""
    text = _SHORT.repr(value)
    return text if len(text) <= limit else text[:limit - 3] + "..."


def existing_path(path: str | Path, what: str = "dataset path") -> Path:
    """``path`` made absolute, with ``~`` expanded, after checking that it exists and is a regular
    file or a folder: a device, FIFO or socket would block or never end when read, so it is refused."""
    try:
        resolved = Path(path).expanduser().resolve()
    except (OSError, RuntimeError, TypeError, ValueError) as exc:
        raise LoaderError(f"{what} {path!r}: cannot resolve it ({exc})") from exc
    try:
        mode = resolved.stat().st_mode
    except (FileNotFoundError, NotADirectoryError):
        raise LoaderError(f"{what} {str(resolved)!r} does not exist") from None
    except OSError as exc:
        raise LoaderError(f"{what} {str(resolved)!r}: {unreadable(exc, resolved)}") from None
    if not (stat.S_ISDIR(mode) or stat.S_ISREG(mode)):
        raise LoaderError(f"{what} {str(resolved)!r} is {special_kind(mode)}, not a file or folder")
    return resolved


def special_kind(mode: int) -> str:
    """What a file that is not a regular file is (a folder, a device, ...), from its ``st_mode``."""
    kinds = ((stat.S_ISDIR, "a folder"), (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
             (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISSOCK, "a socket"))
    return next((name for test, name in kinds if test(mode)), "a special file")


def unreadable(error: OSError, fallback: Path) -> LoaderError:
    """A :class:`LoaderError` for an ``OSError`` met while reading a dataset, in one line: the folder
    that cannot be entered when that is the cause, else the file or folder the error names (else
    ``fallback``), and the reason."""
    path = Path(error.filename) if error.filename else fallback
    closed = next((folder for folder in reversed(path.parents) if not os.access(folder, os.X_OK)), None)
    if closed is not None:
        return LoaderError(f"{closed}: cannot open the folder (Permission denied)")
    what = "the folder" if path.is_dir() else "it"
    return LoaderError(f"{path}: cannot read {what} ({error.strerror or error})")


class LfsPointer(LoaderError):
    """A Git LFS pointer file where the data belongs (a repository cloned without ``git lfs``)."""

    def __init__(self, path: Path) -> None:
        super().__init__(f"{path} is a Git LFS pointer, not the data: run `git lfs pull` in the dataset's repository")
        self.path = path


LFS_POINTER = b"version https://git-lfs.github.com/spec/v1"
LFS_POINTER_MAX_BYTES = 1024
"""A pointer file is a few lines of text (``version``, ``oid sha256:...``, ``size``), well under this."""


def nonempty_file(path: Path) -> Path:
    """``path`` after checking that it is a file with at least one byte that is not a Git LFS pointer."""
    try:
        status = path.stat()
    except OSError as exc:
        raise unreadable(exc, path) from None
    if not stat.S_ISREG(status.st_mode):
        raise LoaderError(f"{path}: {special_kind(status.st_mode)}, not a file")
    size = status.st_size
    if size == 0:
        raise LoaderError(f"{path}: the file is empty")
    if size <= LFS_POINTER_MAX_BYTES and is_lfs_pointer(path):
        raise LfsPointer(path)
    return path


def is_lfs_pointer(path: Path) -> bool:
    """Whether ``path`` is a Git LFS pointer file (``version https://git-lfs.github.com/spec/v1`` first)."""
    try:
        with path.open("rb") as file:
            return file.read(len(LFS_POINTER)) == LFS_POINTER
    except OSError:
        return False
