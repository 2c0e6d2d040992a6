"""The two agents' LiDAR points in the scene (the View tab's "LiDAR points"), for datasets that ship
them (``loaders.Frame.points``): the ego's where the ego is, the CAV's placed like its boxes (so a
wrong pose shows as two clouds that do not overlap, and calibration brings them together)."""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cbm import se2
from loaders import Frame

RGB = tuple[int, int, int]
POINT_SIZE = 0.08
"""Metres: the side of a drawn point."""


@dataclass(frozen=True)
class PointCloud:
    points: np.ndarray
    """(N, 3) float32 in the scene's frame (ego frame, metres)."""
    color: RGB


def no_points() -> np.ndarray:
    return np.zeros((0, 3), np.float32)


def agent_points(frame: Frame | None, agent_id: str | None, poses: Sequence[np.ndarray], every: int) -> np.ndarray:
    """Every ``every``-th point of the agent's LiDAR sweep, once per pose (agent frame -> scene),
    raised by the agent's sensor height; empty when the dataset has no points for it."""
    points = None if frame is None or agent_id is None else frame.points(agent_id)
    if points is None or not len(points):
        return no_points()
    kept = points[::every]
    lifted = kept[:, 2] + _sensor_height(frame, agent_id)
    copies = [np.column_stack([se2.apply_points(pose, kept[:, :2]), lifted]) for pose in poses]
    return np.concatenate(copies).astype(np.float32) if copies else no_points()


def clouds(frame: Frame | None, agents: tuple[str | None, str | None], poses: tuple[list, list],
           every: int, colors: tuple[RGB, RGB]) -> dict[str, PointCloud]:
    """The ``ego_points`` and ``cav_points`` nodes: the agents' points at their poses of each panel."""
    return {f"{role}_points": PointCloud(agent_points(frame, agent, role_poses, every), color)
            for role, agent, role_poses, color in zip(("ego", "cav"), agents, poses, colors)}


def _sensor_height(frame: Frame, agent_id: str) -> float:
    agents = frame.agents
    if agents is None:
        return 0.0
    rows = agents.filter(agents["agent_id"] == str(agent_id))
    return float(rows["z"][0]) if len(rows) else 0.0
