"""SE(2) transforms as (3, 3) homogeneous matrices.

A transform named ``T_a_to_b`` maps a point expressed in frame ``a`` into frame ``b``.
"""
from __future__ import annotations

import numpy as np


def wrap_angle(angle: np.ndarray | float) -> np.ndarray | float:
    """Wrap angles to [-pi, pi)."""
    return (np.asarray(angle) + np.pi) % (2.0 * np.pi) - np.pi


def make(x: float, y: float, yaw: float) -> np.ndarray:
    """The transform that rotates by ``yaw`` (counter-clockwise) and then translates by ``(x, y)``."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.array([[c, -s, x], [s, c, y], [0.0, 0.0, 1.0]])


def yaw_of(T: np.ndarray) -> float:
    """Rotation angle of a transform, in [-pi, pi)."""
    return float(np.arctan2(T[1, 0], T[0, 0]))


def translation_of(T: np.ndarray) -> np.ndarray:
    return np.asarray(T[:2, 2], dtype=float).copy()


def inverse(T: np.ndarray) -> np.ndarray:
    """Inverse of a rigid SE(2) transform."""
    R = T[:2, :2]
    out = np.eye(3)
    out[:2, :2] = R.T
    out[:2, 2] = -R.T @ T[:2, 2]
    return out


def apply_points(T: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Map ``(N, 2)`` points with ``T``."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    return points @ T[:2, :2].T + T[:2, 2]


def apply_boxes(T: np.ndarray, boxes: np.ndarray) -> np.ndarray:
    """Map ``(N, 7)`` boxes ``x, y, z, length, width, height, yaw`` with ``T`` (z and sizes kept)."""
    boxes = np.asarray(boxes, dtype=float)
    out = boxes.copy()
    if len(boxes):
        out[:, :2] = apply_points(T, boxes[:, :2])
        out[:, 6] = wrap_angle(boxes[:, 6] + yaw_of(T))
    return out
