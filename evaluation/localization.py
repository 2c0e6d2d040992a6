"""The localization error models of a trial (``ScenarioParams.localization``): the pose the CAV
reports, from the true one and the trial's draw (``evaluation.scenario``'s step 2)."""
from __future__ import annotations

from typing import Protocol

import numpy as np
from scipy.special import ndtr

from cbm import se2


class ScenarioParams(Protocol):
    """What the models read of ``evaluation.scenario.ScenarioParams``."""

    localization: str
    loc_x: float
    loc_y: float

    @property
    def loc_yaw_rad(self) -> float: ...


def _unguessed(params: ScenarioParams) -> bool:
    """No GNSS and no guess: the CAV reports the ego's own pose, so ``init`` is the identity."""
    return params.localization == "none" and params.loc_x == 0.0


def localization_error(params: ScenarioParams, draw: np.ndarray) -> np.ndarray:
    """(dx, dy, dyaw[rad]) added to the CAV's world pose: fixed (sec. IV-A), ``draw`` scaled (sec. V-A),
    or (none) ``draw`` made uniform: a point of the disc of radius ``loc_x`` and any heading."""
    if params.localization == "none":
        u = ndtr(draw)
        radius, direction = params.loc_x * np.sqrt(u[0]), 2.0 * np.pi * u[1]
        return np.array([radius * np.cos(direction), radius * np.sin(direction), 2.0 * np.pi * u[2] - np.pi])
    size = np.array([params.loc_x, params.loc_y, params.loc_yaw_rad])
    return size if params.localization == "fixed" else size * draw


def reported_cav_pose(params: ScenarioParams, ego_pose: np.ndarray, cav_pose: np.ndarray, draw: np.ndarray,
                      dataset_pose: np.ndarray | None, drifted: np.ndarray | None) -> np.ndarray:
    """The CAV's world pose as it reports it: the true pose plus ``localization_error`` or the
    drifting error ``drifted``, the dataset's own (``localization="dataset"``; a ``ValueError``
    when the frame has none), or, without GNSS and without a guess, the ego's own pose."""
    if _unguessed(params):
        return ego_pose
    if params.localization == "drifting":
        if drifted is None:
            raise ValueError("localization 'drifting' needs the frame's drifting error (FrameInputs.build makes it)")
        return perturbed_pose(cav_pose, drifted)
    if params.localization != "dataset":
        return perturbed_pose(cav_pose, localization_error(params, draw))
    if dataset_pose is None:
        raise ValueError("localization 'dataset' needs the noisy pose the dataset reports for "
                         "the CAV (OPV2V-family releases do); this frame's CAV has none")
    return dataset_pose


def perturbed_pose(pose: np.ndarray, error: np.ndarray) -> np.ndarray:
    """The pose whose world (x, y, yaw) is ``pose``'s plus ``error`` (OpenCOOD-style additive pose noise)."""
    x, y = se2.translation_of(pose) + error[:2]
    return se2.make(x, y, se2.yaw_of(pose) + error[2])
