"""Reading nested JSON / YAML annotation files with errors that name the file and the key."""
from __future__ import annotations

import json
import math
import re
from pathlib import Path

import yaml

from .errors import READ_ERRORS, LoaderError, nonempty_file


class _Loader(yaml.SafeLoader):
    """YAML 1.1 safe loader that also reads ``1e-5`` (no dot) as a float, as OpenCOOD's does."""


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
                   |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
                   |\.[0-9_]+(?:[eE][-+][0-9]+)?
                   |[-+]?\.(?:inf|Inf|INF)
                   |\.(?:nan|NaN|NAN))$""", re.X),
    list("-+0123456789."),
)


def read_yaml(path: Path):
    nonempty_file(path)
    try:
        return yaml.load(path.read_bytes(), Loader=_Loader)
    except (yaml.YAMLError, *READ_ERRORS, RecursionError) as exc:
        raise LoaderError(f"{path}: not valid YAML ({_first_line(exc)})") from exc


def read_json(path: Path):
    nonempty_file(path)
    try:
        return json.loads(path.read_bytes())
    except (*READ_ERRORS, RecursionError) as exc:
        raise LoaderError(f"{path}: not valid JSON ({_first_line(exc)})") from exc


def field(path: Path, mapping, key, where: str = ""):
    """``mapping[key]``, or a :class:`LoaderError` naming the key."""
    name = f"{where}.{key}" if where else str(key)
    if not isinstance(mapping, dict):
        raise LoaderError(f"{path}: {where or 'top level'}: expected a mapping with key {key!r}")
    if key not in mapping:
        raise LoaderError(f"{path}: missing key {name}")
    return mapping[key]


def number(path: Path, value, where: str) -> float:
    """A finite float, or a :class:`LoaderError` naming ``where``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise LoaderError(f"{path}: {where}: expected a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise LoaderError(f"{path}: {where}: expected a finite number, got {value!r}")
    return value


def numbers(path: Path, value, where: str, count: int) -> list[float]:
    """A list of ``count`` finite floats."""
    if not isinstance(value, (list, tuple)) or len(value) < count:
        raise LoaderError(f"{path}: {where}: expected a list of {count} numbers, got {value!r}")
    return [number(path, v, f"{where}[{i}]") for i, v in enumerate(value[:count])]


def matrix(path: Path, value, where: str, rows: int, cols: int) -> list[list[float]]:
    """A ``rows x cols`` nested list of finite floats."""
    if not isinstance(value, (list, tuple)) or len(value) != rows:
        raise LoaderError(f"{path}: {where}: expected {rows} rows of {cols} numbers, got {value!r}")
    out = []
    for i, row in enumerate(value):
        if not isinstance(row, (list, tuple)) or len(row) != cols:
            raise LoaderError(f"{path}: {where}[{i}]: expected {cols} numbers, got {row!r}")
        out.append([number(path, v, f"{where}[{i}][{j}]") for j, v in enumerate(row)])
    return out


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0][:200] if text else type(exc).__name__
