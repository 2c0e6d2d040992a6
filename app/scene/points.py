"""The two agents' LiDAR points in the scene (the View tab's "LiDAR points"), for datasets that ship
them (``loaders.Frame.points``): the ego's where the ego is, the CAV's placed like its boxes (so a
wrong pose shows as two clouds that do not overlap, and calibration brings them together)."""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cbm import se2
from loaders import Frame, LoaderError

RGB = tuple[int, int, int]
POINT_SIZE = 0.08
"""Metres: the side of a drawn point."""


@dataclass(frozen=True)
class PointCloud:
    points: np.ndarray
    """(N, 3) float32 in the scene's frame (ego frame, metres)."""
    color: RGB
    problem: str = ""
    """Why the agent's sweep is not shown although the dataset names one (the reader's one-line
    message, naming the file); empty when it is shown or the dataset has none."""


def no_points() -> np.ndarray:
    return np.zeros((0, 3), np.float32)


def placed(frame: Frame | None, agent_id: str | None, points: np.ndarray | None, poses: Sequence[np.ndarray],
           every: int) -> np.ndarray:
    """Every ``every``-th point of the agent's LiDAR sweep ``points``, once per pose (agent frame ->
    scene), raised by the agent's sensor height; empty when there are none."""
    if points is None or not len(points):
        return no_points()
    kept = points[::every]
    lifted = kept[:, 2] + _sensor_height(frame, agent_id)
    copies = [np.column_stack([se2.apply_points(pose, kept[:, :2]), lifted]) for pose in poses]
    return np.concatenate(copies).astype(np.float32) if copies else no_points()


def clouds(frame: Frame | None, agents: tuple[str | None, str | None], poses: tuple[list, list],
           every: int, colors: tuple[RGB, RGB]) -> dict[str, PointCloud]:
    """The ``ego_points`` and ``cav_points`` nodes: the agents' points at their poses of each panel.
    A sweep that cannot be read gives an empty node with its ``problem``: the frame's boxes and
    CBM's result never depend on the points."""
    out = {}
    for role, agent, role_poses, color in zip(("ego", "cav"), agents, poses, colors):
        try:
            points, problem = None if frame is None or agent is None else frame.points(agent), ""
        except (LoaderError, OSError) as exc:
            points, problem = None, str(exc)
        out[f"{role}_points"] = PointCloud(placed(frame, agent, points, role_poses, every), color, problem)
    return out


def problems_markdown(drawn: dict[str, PointCloud]) -> str:
    """The lines the metrics panel adds for sweeps that could not be read (empty when none)."""
    problems = [f"- {name.split('_')[0]}: {cloud.problem}" for name, cloud in drawn.items() if cloud.problem]
    if not problems:
        return ""
    return "\n\n**LiDAR points not shown** (the boxes and CBM's result are):\n" + "\n".join(problems)


def _sensor_height(frame: Frame, agent_id: str) -> float:
    agents = frame.agents
    if agents is None:
        return 0.0
    rows = agents.filter(agents["agent_id"] == str(agent_id))
    return float(rows["z"][0]) if len(rows) else 0.0
