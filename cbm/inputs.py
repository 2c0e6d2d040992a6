"""Checks of what callers pass in: a ValueError that names the argument and what was expected."""
from __future__ import annotations

import math
import numbers
import reprlib

import numpy as np

_SHORT = reprlib.Repr()
_SHORT.maxstring, _SHORT.maxother, _SHORT.maxlong = 60, 60, 40
SHOWN_CHARS = 80
"""Longest value a message quotes (a list of a million boxes is not repeated back)."""


def shown(value: object) -> str:
    """``value`` as a message quotes it: its repr, long and nested parts cut, at most ``SHOWN_CHARS``."""
    text = _SHORT.repr(value)
    return text if len(text) <= SHOWN_CHARS else text[:SHOWN_CHARS - 3] + "..."


def is_number(value: object) -> bool:
    """A real number, Python's or numpy's (``np.float32(3)``, ``np.int64(5)``), not a bool."""
    return isinstance(value, numbers.Real) and not isinstance(value, (bool, np.bool_))


def _plain(owner: object, name: str, value: numbers.Real, kind: type) -> None:
    """Store a numpy number given for a field as the Python number it is (``kind``)."""
    if isinstance(value, np.generic):
        object.__setattr__(owner, name, kind(value))


def _real_array(name: str, value: object) -> np.ndarray:
    """``value`` as a float64 array, or ValueError naming ``name``: complex numbers (their imaginary
    part would be dropped), text and other objects are refused."""
    try:
        array = np.asarray(value)
    except ValueError as exc:
        raise ValueError(f"{name} must be an array of real numbers ({exc})") from None
    if array.dtype.kind not in "biuf":
        raise ValueError(f"{name} must be an array of real numbers, got dtype {array.dtype}")
    return array.astype(float)


def checked_boxes(name: str, boxes: np.ndarray) -> np.ndarray:
    """``boxes`` as a finite (N, 7) float64 array (an empty input becomes (0, 7))."""
    array = _real_array(name, boxes)
    if array.size == 0:
        array = array.reshape(0, 7)
    if array.ndim != 2 or array.shape[1] != 7:
        raise ValueError(f"{name} must be an (N, 7) array of x, y, z, length, width, height, yaw; "
                         f"got shape {array.shape}")
    if not np.isfinite(array).all():
        row = int(np.flatnonzero(~np.isfinite(array).all(axis=1))[0])
        raise ValueError(f"{name} must be finite; row {row} is {array[row].tolist()}")
    return array


def checked_transform(name: str, T: np.ndarray) -> np.ndarray:
    """``T`` as a finite rigid (3, 3) SE(2) matrix."""
    array = _real_array(name, T)
    if array.shape != (3, 3) or not np.isfinite(array).all():
        raise ValueError(f"{name} must be a finite (3, 3) SE(2) matrix; got shape {array.shape}")
    (a, b, _), (c, d, _), last = array.tolist()
    orthonormal = max(abs(a * a + c * c - 1.0), abs(b * b + d * d - 1.0), abs(a * b + c * d)) <= 1e-6
    if not (orthonormal and a * d - b * c > 0 and max(abs(last[0]), abs(last[1]), abs(last[2] - 1.0)) <= 1e-8):
        raise ValueError(f"{name} must be a rigid SE(2) transform (rotation block orthonormal, last row 0 0 1)")
    return array


def check_at_most(owner: object, most: dict[str, float]) -> None:
    """ValueError unless each field of ``owner`` named in ``most`` is at most its bound: a parameter's
    one range, wherever it is given (a slider, a preset, ``--grid``, a search), ends there."""
    for name, bound in most.items():
        value = getattr(owner, name)
        if is_number(value) and value > bound:
            raise ValueError(f"{type(owner).__name__}.{name} must be at most {bound:g}, got {shown(value)}")


def check_positive(owner: object, *names: str) -> None:
    """ValueError unless each named field of ``owner`` is a positive finite number (a numpy one is
    stored as a Python float)."""
    for name in names:
        value = getattr(owner, name)
        if not is_number(value) or not math.isfinite(value) or value <= 0:
            raise ValueError(f"{type(owner).__name__}.{name} must be a positive finite number, got {shown(value)}")
        _plain(owner, name, value, float)


def check_integer(owner: object, name: str, least: int, most: int) -> None:
    """ValueError unless the named field of ``owner`` is a whole number from ``least`` to ``most``
    (a numpy one is stored as a Python int)."""
    value = getattr(owner, name)
    if not isinstance(value, numbers.Integral) or isinstance(value, (bool, np.bool_)) or not least <= value <= most:
        raise ValueError(f"{type(owner).__name__}.{name} must be an integer from {least} to {most}, "
                         f"got {shown(value)}")
    _plain(owner, name, value, int)
