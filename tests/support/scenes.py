"""Small world scenes for the cbm tests: street-like objects with a minimum spacing."""
from __future__ import annotations

import numpy as np


def street_scene(n: int, rng: np.random.Generator, extent: float = 60.0, spacing: float = 4.0) -> np.ndarray:
    """(n, 7) car-sized boxes at least ``spacing`` apart, heading along two street directions."""
    points: list[np.ndarray] = []
    while len(points) < n:
        p = rng.uniform(-extent, extent, 2)
        if all(np.hypot(*(p - q)) > spacing for q in points):
            points.append(p)
    boxes = np.zeros((n, 7))
    if n:
        boxes[:, :2] = np.array(points)
    boxes[:, 3:6] = (4.5, 1.9, 1.6)
    boxes[:, 6] = rng.choice([0.0, np.pi / 2, np.pi, -np.pi / 2], n) + rng.normal(0, 0.1, n)
    return boxes


def dense_scene(n: int, rng: np.random.Generator, spacing: float = 5.0) -> np.ndarray:
    """(n, 7) car-sized boxes on a jittered square lattice ``spacing`` apart, any heading: a car park
    rather than streets, where context vectors spread evenly and the join's cells fill up."""
    side = int(np.ceil(np.sqrt(n)))
    lattice = np.stack(np.meshgrid(np.arange(side), np.arange(side)), axis=-1).reshape(-1, 2) * spacing
    chosen = lattice[rng.permutation(len(lattice))[:n]] + rng.uniform(-spacing / 4, spacing / 4, (n, 2))
    boxes = np.zeros((n, 7))
    boxes[:, :2] = chosen - chosen.mean(axis=0) if n else chosen
    boxes[:, 3:6] = (4.5, 1.9, 1.6)
    boxes[:, 6] = rng.uniform(-np.pi, np.pi, n)
    return boxes
