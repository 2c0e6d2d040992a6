"""Checks of what callers pass in: a ValueError that names the argument and what was expected."""
from __future__ import annotations

import math

import numpy as np


def checked_boxes(name: str, boxes: np.ndarray) -> np.ndarray:
    """``boxes`` as a finite (N, 7) float64 array (an empty input becomes (0, 7))."""
    array = np.asarray(boxes, dtype=float)
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
    array = np.asarray(T, dtype=float)
    if array.shape != (3, 3) or not np.isfinite(array).all():
        raise ValueError(f"{name} must be a finite (3, 3) SE(2) matrix; got shape {array.shape}")
    rotation = array[:2, :2]
    if not (np.allclose(rotation.T @ rotation, np.eye(2), atol=1e-6) and np.linalg.det(rotation) > 0
            and np.allclose(array[2], [0.0, 0.0, 1.0])):
        raise ValueError(f"{name} must be a rigid SE(2) transform (rotation block orthonormal, last row 0 0 1)")
    return array


def check_at_most(owner: object, most: dict[str, float]) -> None:
    """ValueError unless each field of ``owner`` named in ``most`` is at most its bound: a parameter's
    one range, wherever it is given (a slider, a preset, ``--grid``, a search), ends there."""
    for name, bound in most.items():
        value = getattr(owner, name)
        if isinstance(value, (int, float)) and not isinstance(value, bool) and value > bound:
            raise ValueError(f"{type(owner).__name__}.{name} must be at most {bound:g}, got {value!r}")


def check_positive(owner: object, *names: str) -> None:
    """ValueError unless each named field of ``owner`` is a positive finite number."""
    for name in names:
        value = getattr(owner, name)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
            raise ValueError(f"{type(owner).__name__}.{name} must be a positive finite number, got {value!r}")
