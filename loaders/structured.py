"""Reading nested JSON / YAML annotation files with errors that name the file and the key."""
from __future__ import annotations

import codecs
import json
import math
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any, BinaryIO, NoReturn

import numpy as np
import yaml

from .errors import READ_ERRORS, LoaderError, nonempty_file, shown

MAX_EXPANDED_VALUES = 1_000_000
"""Most values a YAML document may stand for once its aliases are expanded. ``yaml.dump`` writes
an alias where one list is shared (``&id001`` ... ``*id001``), so aliases are read; but ten nested
levels of ten aliases each stand for 10^10 values in 2 KB (a "billion laughs"), which any reader
walking the value never finishes (issue 50, item 3). A frame of a real dataset is a few thousand."""


def expanded_values(root: yaml.Node) -> int:
    """How many values ``root`` stands for with every alias expanded (a shared node counted each
    time it is referred to), without expanding them; ``ComposerError`` past ``MAX_EXPANDED_VALUES``
    or when an alias refers to a value that holds it."""
    sizes: dict[int, int] = {}
    stack: list[tuple[yaml.Node, bool]] = [(root, False)]
    while stack:
        node, children_done = stack.pop()
        if id(node) in sizes:
            continue
        children = [part for pair in node.value for part in pair] if isinstance(node, yaml.MappingNode) else \
            node.value if isinstance(node, yaml.SequenceNode) else []
        if children_done:
            sizes[id(node)] = 1 + sum(sizes[id(child)] for child in children)
            if sizes[id(node)] > MAX_EXPANDED_VALUES:
                raise yaml.composer.ComposerError(None, None, f"its aliases expand to more than "
                                                  f"{MAX_EXPANDED_VALUES:,} values; not read", node.start_mark)
            continue
        if any(id(child) not in sizes and any(n is child for n, done in stack if done) for child in children):
            raise yaml.composer.ComposerError(None, None, "an alias refers to a value that holds it", node.start_mark)
        stack.append((node, True))
        stack.extend((child, False) for child in children if id(child) not in sizes)
    return sizes[id(root)]


class _Loader(yaml.SafeLoader):
    """YAML 1.1 safe loader that also reads ``1e-5`` (no dot) as a float, as OpenCOOD's does, and the
    tags ``yaml.dump`` writes for numpy numbers and arrays (V2V4Real's files) as plain numbers and
    nested lists; no other Python tag is read. A document whose aliases expand beyond
    ``MAX_EXPANDED_VALUES`` values is refused before any value is built."""

    def compose_document(self) -> yaml.Node:
        node = super().compose_document()
        expanded_values(node)
        return node


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
                   |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
                   |\.[0-9_]+(?:[eE][-+][0-9]+)?
                   |[-+]?\.(?:inf|Inf|INF)
                   |\.(?:nan|NaN|NAN))$""", re.X),
    list("-+0123456789."),
)


NUMPY_MODULES = ("numpy.core.multiarray", "numpy._core.multiarray")
"""Where numpy's ``scalar`` and ``_reconstruct`` live (numpy 1 / numpy 2), as the tags name them."""
NUMBER_KINDS = "biuf"
"""dtype kinds read from numpy tags: booleans, integers, floats (never objects, which pickle)."""


def _refuse(node: yaml.Node, what: str) -> yaml.constructor.ConstructorError:
    return yaml.constructor.ConstructorError(None, None, f"{node.tag}: {what}", node.start_mark)


def _apply_parts(loader: _Loader, node: yaml.Node) -> tuple[list, list]:
    """``(args, state)`` of a ``!!python/object/apply`` node (a sequence of args, or a mapping)."""
    if isinstance(node, yaml.SequenceNode):
        return loader.construct_sequence(node, deep=True), []
    if isinstance(node, yaml.MappingNode):
        parts = loader.construct_mapping(node, deep=True)
        return list(parts.get("args") or []), list(parts.get("state") or [])
    raise _refuse(node, "expected arguments")


def _numpy_apply(loader: _Loader, suffix: str, node: yaml.Node):
    """A numpy dtype, number (a Python int / float / bool) or array (nested lists) from the tag
    ``!!python/object/apply:<suffix>``; any other callable is refused."""
    module, _, name = suffix.rpartition(".")
    if suffix != "numpy.dtype" and (module not in NUMPY_MODULES or name not in ("scalar", "_reconstruct")):
        raise _refuse(node, "not read (only numpy numbers and arrays are)")
    args, state = _apply_parts(loader, node)
    try:
        if suffix == "numpy.dtype":
            return _dtype(args, state)
        if name == "scalar":
            dtype, raw = args
            return np.frombuffer(raw, dtype, count=1)[0].item()
        _version, shape, dtype, fortran, raw = state
        return np.frombuffer(raw, dtype).reshape(shape, order="F" if fortran else "C").tolist()
    except (TypeError, ValueError, IndexError) as exc:
        raise _refuse(node, f"expected a numpy number or array as yaml.dump writes it ({exc})") from exc


def _dtype(args: list, state: list) -> np.dtype:
    dtype = np.dtype(args[0])
    if dtype.kind not in NUMBER_KINDS:
        raise ValueError(f"dtype {shown(args[0])} is not a number type")
    order = state[1] if len(state) > 1 else "="
    return dtype.newbyteorder(order) if order in "<>" else dtype


def _numpy_name(loader: _Loader, suffix: str, node: yaml.Node) -> str:
    if suffix != "numpy.ndarray":
        raise _refuse(node, "not read (only numpy.ndarray is)")
    return suffix


_Loader.add_multi_constructor("tag:yaml.org,2002:python/object/apply:", _numpy_apply)
_Loader.add_multi_constructor("tag:yaml.org,2002:python/name:", _numpy_name)
_Loader.add_constructor("tag:yaml.org,2002:python/tuple", lambda loader, node: loader.construct_sequence(node))


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
        raise LoaderError(f"{path}: {where}: expected a number, got {shown(value)}")
    value = float(value)
    if not math.isfinite(value):
        raise LoaderError(f"{path}: {where}: expected a finite number, got {shown(value)}")
    return value


def numbers(path: Path, value, where: str, count: int) -> list[float]:
    """A list of ``count`` finite floats."""
    if not isinstance(value, (list, tuple)) or len(value) < count:
        raise LoaderError(f"{path}: {where}: expected a list of {count} numbers, got {shown(value)}")
    return [number(path, v, f"{where}[{i}]") for i, v in enumerate(value[:count])]


def matrix(path: Path, value, where: str, rows: int, cols: int) -> list[list[float]]:
    """A ``rows x cols`` nested list of finite floats."""
    if not isinstance(value, (list, tuple)) or len(value) != rows:
        raise LoaderError(f"{path}: {where}: expected {rows} rows of {cols} numbers, got {shown(value)}")
    out = []
    for i, row in enumerate(value):
        if not isinstance(row, (list, tuple)) or len(row) != cols:
            raise LoaderError(f"{path}: {where}[{i}]: expected {cols} numbers, got {row!r}")
        out.append([number(path, v, f"{where}[{i}][{j}]") for j, v in enumerate(row)])
    return out


MAX_METRES = 1e6
"""Largest position or size, in metres, a file may give (1000 km: beyond any scene; finite values as
large as 1e300 would overflow the trials far from the file)."""
ROTATION_TOLERANCE = 1e-3
"""Largest entry of ``R R^T - I``, and of ``det R - 1``, for a matrix that is read as a rotation."""


def rotation(path: Path, value, where: str) -> np.ndarray:
    """A 3x3 rotation (orthonormal, determinant 1, within :data:`ROTATION_TOLERANCE`), or a
    ``LoaderError`` naming the field."""
    R = np.array(matrix(path, value, where, 3, 3))
    if not is_rotation(R):
        raise LoaderError(f"{path}: {where}: expected a rotation (orthonormal rows, determinant 1), "
                          f"got {R.round(3).tolist()}")
    return R


def rigid(path: Path, value, where: str) -> np.ndarray:
    """A 4x4 rigid transform (a rotation in its upper-left 3x3), or a ``LoaderError`` naming ``where``."""
    m = np.array(matrix(path, value, where, 4, 4))
    if not is_rotation(m[:3, :3]):
        raise LoaderError(f"{path}: {where}: expected a rigid 4x4 transform (a rotation in its upper-left 3x3), "
                          f"got {m.round(3).tolist()}")
    return m


def is_rotation(R: np.ndarray) -> bool:
    """Whether ``R`` is a rotation within :data:`ROTATION_TOLERANCE`."""
    return bool(np.abs(R @ R.T - np.eye(3)).max() <= ROTATION_TOLERANCE
                and abs(np.linalg.det(R) - 1.0) <= ROTATION_TOLERANCE)


def metres(path: Path, value, where: str) -> float:
    """A finite number of metres no larger in size than :data:`MAX_METRES`, or a ``LoaderError``."""
    out = number(path, value, where)
    if abs(out) > MAX_METRES:
        raise LoaderError(f"{path}: {where}: expected at most {MAX_METRES:.0e} metres in size, got {out:g}")
    return out


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    return text[0][:200] if text else type(exc).__name__


STREAM_CHUNK = 1 << 20
"""Characters read at a time by :func:`json_object_items` (more while one entry is longer)."""
MAX_ENTRY_CHARS = 64 << 20
"""Characters one entry of a streamed JSON object may take: beyond, the file is refused."""
_SPACE = re.compile(r"[ \t\n\r]*")


def json_object_items(path: Path, expected: str) -> Iterator[tuple[str, Any]]:
    """The entries of a file holding one JSON object, parsed one at a time, so that memory holds one
    entry rather than the whole file (a detector's 300 MB of boxes would take over 4 GB as Python
    objects). Duplicate keys are all yielded. ``LoaderError`` names the file and what is wrong;
    ``expected`` says what the object should be."""
    nonempty_file(path)
    try:
        with path.open("rb") as file:
            yield from _ObjectStream(path, file, expected).items()
    except (OSError, UnicodeDecodeError, RecursionError) as exc:
        raise LoaderError(f"{path}: not valid JSON ({_first_line(exc)})") from exc


class _ObjectStream:
    """A JSON object read from a binary file chunk by chunk (``json.JSONDecoder.raw_decode`` per value)."""

    def __init__(self, path: Path, file: BinaryIO, expected: str) -> None:
        self.path, self.file, self.expected = path, file, expected
        self.decode = codecs.getincrementaldecoder("utf-8-sig")().decode
        self.decoder = json.JSONDecoder()
        self.text, self.at, self.consumed, self.ended = "", 0, 0, False

    def items(self) -> Iterator[tuple[str, Any]]:
        """Every ``key, value`` of the object, in file order."""
        if self._next_char() != "{":
            raise LoaderError(f"{self.path}: expected {self.expected}")
        self.at += 1
        if self._next_char() == "}":
            self.at += 1
            return self._end()
        while True:
            key = self._value()
            if not isinstance(key, str) or self._next_char() != ":":
                self._invalid("expected a string key and ':'")
            self.at += 1
            yield key, self._value()
            separator = self._next_char()
            self.at += 1
            if separator == "}":
                return self._end()
            if separator != ",":
                self._invalid("expected ',' or '}' after a value")

    def _end(self) -> None:
        """After the closing brace (consumed): nothing but white space may follow."""
        if self._next_char():
            self._invalid("extra data after the object")

    def _fill(self) -> bool:
        """Read more of the file (at least as much as is pending); False at its end."""
        if self.ended:
            return False
        pending = self.text[self.at:]
        if len(pending) > MAX_ENTRY_CHARS:
            raise LoaderError(f"{self.path}: an entry near character {self.consumed + self.at} is over "
                              f"{MAX_ENTRY_CHARS >> 20} M characters; expected {self.expected}")
        chunk = self.file.read(max(STREAM_CHUNK, len(pending)))
        if not chunk:
            self.ended = True
            self.decode(b"", final=True)
            return False
        self.consumed += self.at
        self.text, self.at = pending + self.decode(chunk), 0
        return True

    def _next_char(self) -> str:
        """The next character that is not white space ("" at the end of the file), not consumed."""
        while True:
            self.at = _SPACE.match(self.text, self.at).end()
            if self.at < len(self.text) or not self._fill():
                return self.text[self.at:self.at + 1]

    def _value(self) -> Any:
        """The JSON value at the cursor, reading on until it is complete."""
        self._next_char()
        while True:
            try:
                value, end = self.decoder.raw_decode(self.text, self.at)
            except json.JSONDecodeError as exc:
                if self._fill():
                    continue
                self._invalid(exc.msg)
            except ValueError as exc:  # an integer of more digits than Python converts
                self._invalid(_first_line(exc).split(":")[0])
            if end < len(self.text) or not self._fill():
                self.at = end
                return value

    def _invalid(self, reason: str) -> NoReturn:
        raise LoaderError(f"{self.path}: not valid JSON ({reason} near character {self.consumed + self.at})")
