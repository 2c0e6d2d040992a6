"""Clutter in a trial: detections an agent misses and false boxes it reports (``ScenarioParams.miss_rate``,
``ScenarioParams.false_rate``), the conditions where few objects are shared and many boxes pair with nothing.

A false box is placed where the agent could have seen an object: uniformly over its sensor disc (range
protocol) or over the bounding rectangle of its real detections (other protocols). Its size is one of
the agent's real boxes' (so a size test cannot tell it apart) and its heading is uniform. Its id is
``false:<agent>:<k>``, so it is in no true pair.
"""
from __future__ import annotations

import dataclasses
import math
from typing import TypeVar

import numpy as np

from cbm import se2

Trial = TypeVar("Trial")
"""A ``evaluation.scenario.Trial`` (not imported: ``evaluation.scenario`` uses this module)."""

FALSE_PREFIX = "false:"
"""How a false box's id begins (``false:<agent>:<k>``)."""
FALSE_DRAWS = 4
"""Uniform draws per false box: two for its centre, one for the box whose size it copies, one for its heading."""


def false_box_count(n_detections: int, false_rate: float) -> int:
    """How many false boxes an agent with ``n_detections`` real detections reports: ``round(rate * n)``."""
    return int(round(false_rate * n_detections))


def false_boxes(real: np.ndarray, draws: np.ndarray, sensor_range: float | None) -> np.ndarray:
    """(F, 7) false boxes in the agent's frame from ``draws`` ((F, ``FALSE_DRAWS``) uniforms in [0, 1)):
    centres uniform over the disc of ``sensor_range`` around the agent (when given) or over the
    bounding rectangle of the ``real`` boxes' centres, sizes copied from ``real``, headings uniform."""
    if len(draws) == 0 or len(real) == 0:
        return np.zeros((0, 7))
    if sensor_range is not None:
        radius, angle = sensor_range * np.sqrt(draws[:, 0]), 2.0 * math.pi * draws[:, 1]
        xy = np.stack([radius * np.cos(angle), radius * np.sin(angle)], axis=1)
    else:
        low, high = real[:, :2].min(axis=0), real[:, :2].max(axis=0)
        xy = low + draws[:, :2] * (high - low)
    boxes = real[np.minimum((draws[:, 2] * len(real)).astype(np.intp), len(real) - 1)].copy()
    boxes[:, :2] = xy
    boxes[:, 6] = se2.wrap_angle(2.0 * math.pi * draws[:, 3])
    return boxes


def with_false_boxes(trial: Trial, rng: np.random.Generator, false_rate: float,
                     sensor_range: float | None) -> Trial:
    """``trial`` with each agent's false boxes appended after its real detections (ego's drawn
    first, then the CAV's), so the true pairs keep their indices. Ids become text: ``false:<agent>:<k>``."""
    changes = {}
    for role in ("ego", "cav"):
        real = getattr(trial, f"{role}_boxes")
        draws = rng.random((false_box_count(len(real), false_rate), FALSE_DRAWS))
        added = false_boxes(real, draws, sensor_range)
        ids = [f"{FALSE_PREFIX}{role}:{k}" for k in range(len(added))]
        true_xy = added[:, :2] if role == "ego" else se2.apply_points(trial.T_true, added[:, :2])
        changes[f"{role}_boxes"] = np.concatenate([real, added])
        changes[f"{role}_ids"] = np.concatenate([getattr(trial, f"{role}_ids").astype(str), np.array(ids, dtype=str)])
        changes[f"{role}_true_xy"] = np.concatenate([getattr(trial, f"{role}_true_xy"), true_xy.reshape(-1, 2)])
    return dataclasses.replace(trial, **changes)


def missed(draws: np.ndarray, miss_rate: float) -> np.ndarray:
    """Mask of the detections an agent misses: those whose uniform draw is below ``miss_rate``."""
    return draws < miss_rate


def is_false(ids: np.ndarray) -> np.ndarray:
    """Mask of the false boxes among a trial's detection ``ids`` (``with_false_boxes``'s ids)."""
    return np.char.startswith(np.asarray(ids).astype(str), FALSE_PREFIX)
