"""Preset files, read the same way by the app and the command line: named settings as TOML, as CBM
Explorer saves and exports them and as ``presets/`` ships them.

A preset holds an optional ``description`` and ``name``, the ``method`` shown, a ``[scenario]``
table (the fields of ``ScenarioParams``, angles in degrees), one table per method parameter set
(``[cbm]``, ``[icp]``, ``[ricp]``, ``[vips]``: ``Method.params_key``), ``[tracking]`` (the fields
of ``cbm.TrackingParams``: how CBM over time follows a CAV's pose error) and the app's ``[view]``,
which only the app reads. Keys a preset leaves out keep the values of the preset it is read over:
the shipped ``default`` preset gives both the app and ``evaluate.py`` their defaults.

    from evaluation.presets import default_preset, read_preset_file
    params = read_preset_file("my-tuning.toml")  # PresetParams over the default preset
"""
from __future__ import annotations

import dataclasses
import functools
import os
import re
import stat
import sys
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from cbm import TrackingParams
from cbm.methods import METHODS
from loaders.errors import special_kind, unreadable
from presets import SHIPPED_DIR

from .scenario import ScenarioParams

if sys.version_info >= (3, 11):
    import tomllib
else:
    import tomli as tomllib

DEFAULT = "default"
"""The shipped preset whose values are everyone's defaults."""
MAX_BYTES = 256 * 1024
"""Largest preset file read (a saved preset is about 1 kB)."""
MAX_DEPTH = 16
"""Deepest nesting of arrays and inline tables read (a saved preset has 2)."""
ABOUT_KEYS = ("description", "name")
"""Keys that describe a preset rather than set anything."""
_STRINGS_AND_COMMENTS = re.compile(r'"""[\s\S]*?"""|\'\'\'[\s\S]*?\'\'\'|"(?:[^"\\\n]|\\.)*"|\'[^\'\n]*\'|#[^\n]*')


class PresetError(ValueError):
    """A preset that cannot be read or saved; the message names the file and, where one is at
    fault, the key."""


class NotRegularFile(OSError):
    """A path that is a folder, device, FIFO or socket where a regular file was expected."""


def read_regular(path: Path, limit: int) -> bytes:
    """Up to ``limit + 1`` bytes of ``path``, refused with :class:`NotRegularFile` (saying what it is)
    unless it is a regular file. The file is opened without blocking and checked on the open file
    itself, so a FIFO or a device never blocks the reader, even one put in place after a listing."""
    descriptor = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    try:
        mode = os.fstat(descriptor).st_mode
        if not stat.S_ISREG(mode):
            raise NotRegularFile(f"{special_kind(mode)}, not a regular file")
        os.set_blocking(descriptor, True)
        with os.fdopen(descriptor, "rb", closefd=False) as handle:
            return handle.read(limit + 1)
    finally:
        os.close(descriptor)


def code_defaults() -> dict[str, Any]:
    """Every method's default parameter set by its key (methods that share a set appear once)."""
    return {m.params_key: m.params() for m in METHODS.values()}


@dataclass(frozen=True)
class PresetParams:
    """What a preset sets for a run: the method shown, the scenario and every method's parameters."""

    method: str = "cbm"
    scenario: ScenarioParams = ScenarioParams()
    params: Mapping[str, Any] = field(default_factory=code_defaults)
    """Parameters of every method by ``Method.params_key``."""
    tracking: TrackingParams = TrackingParams()
    """How a method over time (``cbm-time``) tracks the CAV's pose error from frame to frame."""


def replaced(table: str, value: Any, changes: Any) -> Any:
    """The dataclass ``value`` with the keys of the TOML table ``changes`` replaced, each checked
    against the field's type (an integer reads as a float); ``KeyError`` naming an unknown key,
    ``TypeError`` a value of the wrong type, ``ValueError`` one the dataclass refuses."""
    if not isinstance(changes, Mapping):
        raise TypeError(f"[{table}] must be a table of keys, got {type(changes).__name__}")
    fields = {f.name: f for f in dataclasses.fields(value)}
    for key, new in changes.items():
        if key not in fields:
            raise KeyError(f"[{table}] unknown key {key!r}; expected one of {sorted(fields)}")
        old = getattr(value, key)
        expected = float if isinstance(old, float) and not isinstance(old, bool) else type(old)
        allowed = (int, float) if expected is float else expected
        if isinstance(new, bool) != isinstance(old, bool) or not isinstance(new, allowed):
            raise TypeError(f"[{table}] {key} must be {expected.__name__}, got {new!r}")
    try:
        return dataclasses.replace(value, **{k: float(v) if isinstance(getattr(value, k), float) else v
                                             for k, v in changes.items()})
    except ValueError as error:
        raise ValueError(f"[{table}] {error}") from None


def preset_params(tables: Mapping[str, Any], base: PresetParams | None = None,
                  other_tables: Iterable[str] = ("view",)) -> PresetParams:
    """The preset ``tables`` (without ``description`` and ``name``) over ``base`` (default: the
    code's defaults). ``other_tables`` are known and left to their reader (the app's ``[view]``);
    ``KeyError``, ``TypeError`` or ``ValueError`` name the table and key at fault."""
    base = base or PresetParams()
    known = {"method", "scenario", "tracking", *base.params, *other_tables}
    for table in tables:
        if table not in known:
            raise KeyError(f"unknown table [{table}]; expected one of {sorted(known)}")
    method = tables.get("method", base.method)
    if method not in METHODS:
        raise ValueError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    params = {key: replaced(key, value, tables[key]) if key in tables else value for key, value in base.params.items()}
    return PresetParams(method, replaced("scenario", base.scenario, tables.get("scenario", {})), params,
                        replaced("tracking", base.tracking, tables.get("tracking", {})))


def nesting_depth(text: str) -> int:
    """How deep arrays and tables nest in TOML ``text`` (brackets outside strings and comments)."""
    code = np.frombuffer(_STRINGS_AND_COMMENTS.sub("", text).encode("utf-8"), dtype=np.uint8)
    steps = np.isin(code, (ord("["), ord("{"))).astype(np.int64) - np.isin(code, (ord("]"), ord("}")))
    return int(np.cumsum(steps).max(initial=0))


def read_toml(path: Path, shown: str | None = None) -> dict[str, Any]:
    """The whole preset document at ``path``, read the one way the app and the command line read a
    preset: a regular file only (never blocking on a FIFO), of at most ``MAX_BYTES``, UTF-8 (a byte
    order mark, as some editors save, is passed over), nested
    at most ``MAX_DEPTH`` deep, TOML; else ``PresetError`` naming the file as ``shown`` (its path)."""
    shown = str(path) if shown is None else shown
    try:
        data = read_regular(path, MAX_BYTES)
    except NotRegularFile as error:
        raise PresetError(f"{shown}: {error}; not read") from None
    except OSError as error:
        raise PresetError(f"{shown}: cannot be read ({error.strerror or error})") from None
    if len(data) > MAX_BYTES:
        raise PresetError(f"{shown}: larger than {MAX_BYTES // 1024} KB; not read")
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise PresetError(f"{shown}: not UTF-8 text (UnicodeDecodeError at byte {error.start})") from None
    if nesting_depth(text) > MAX_DEPTH:
        raise PresetError(f"{shown}: nested deeper than {MAX_DEPTH} levels; not read")
    try:
        return tomllib.loads(text)
    except (tomllib.TOMLDecodeError, RecursionError) as error:
        raise PresetError(f"{shown}: not a TOML preset ({type(error).__name__}: {error})") from None


def preset_tables(path: Path) -> dict[str, Any]:
    """The tables of the preset file ``path`` (``description`` and ``name`` left out), ``read_toml``'s."""
    return {key: value for key, value in read_toml(path).items() if key not in ABOUT_KEYS}


def read_preset_file(path: Path | str, base: PresetParams | None = None) -> PresetParams:
    """The preset file ``path`` over ``base`` (default: the shipped default preset);
    ``PresetError`` with one line naming the file and the key at fault."""
    path = Path(path)
    try:
        return preset_params(preset_tables(path), default_preset() if base is None else base)
    except (KeyError, TypeError, ValueError) as error:
        if isinstance(error, PresetError):
            raise
        raise PresetError(f"{path}: {error.args[0] if error.args else error}") from None


def shipped_path(name: str) -> Path | None:
    """The file of the shipped preset ``name``, or None when there is none of that name."""
    path = SHIPPED_DIR / f"{name}.toml"
    return path if name and "/" not in name and "\\" not in name and path.is_file() else None


def shipped_names() -> list[str]:
    return sorted(path.stem for path in SHIPPED_DIR.glob("*.toml"))


def find_preset(name_or_file: str) -> PresetParams:
    """The preset file at ``name_or_file``, else the shipped preset of that name, over the default
    preset; ``PresetError`` when it is neither, or cannot be read."""
    path = Path(name_or_file)
    try:
        found = path.exists()
    except OSError as error:
        raise PresetError(str(unreadable(error, path))) from None
    if not found:
        shipped = shipped_path(name_or_file)
        if shipped is None:
            raise PresetError(f"{name_or_file!r} is neither a preset file nor a shipped preset "
                                  f"({', '.join(shipped_names())})")
        path = shipped
    return read_preset_file(path)


@functools.lru_cache(maxsize=1)
def default_preset() -> PresetParams:
    """The shipped ``default`` preset over the code's defaults: the app's settings and the
    command line's when nothing else is asked for."""
    return read_preset_file(SHIPPED_DIR / f"{DEFAULT}.toml", PresetParams())
