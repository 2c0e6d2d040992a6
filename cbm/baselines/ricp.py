"""RICP baseline: robust point-to-point ICP with Welsch weights (Zhang, Yao and Deng, "Fast and Robust
Iterative Closest Point", TPAMI 2022), on box centres."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from .. import se2
from ..estimate import weighted_procrustes
from ..inputs import check_at_most, check_positive
from ..result import MatchResult
from ._common import check_count, check_params, closest_point_match

_SCALE_NEIGHBOURS = 7
"""FRICP's ``FindKnearestMed(kdtree, Y, 7)``: each target point and its 6 nearest neighbours."""
_MIN_WEIGHT = 1e-12
"""Weights below this count as zero when deciding whether a fit is still determined."""


@dataclass(frozen=True)
class RICPParams:
    """Parameters of RICP; defaults are those of the authors' released code (FRICP ``ICP::Parameters``
    and the ``RICP`` method of its ``main.cpp``, which turns Anderson acceleration on)."""

    max_iterations: int = 100
    """Most reweighted fits per Welsch scale nu (``max_icp``)."""
    tolerance: float = 1e-5
    """Next scale when the Frobenius norm of the change of the (3, 3) transform falls below this (``stop``)."""
    nu_begin_k: float = 3.0
    """The first nu is this times the median closest-point distance under ``init``."""
    nu_end_k: float = 1.0 / (3.0 * math.sqrt(3.0))
    """The floor of nu is this times the median spacing of the ego centres to their 6 nearest neighbours."""
    nu_alpha: float = 0.5
    """nu is multiplied by this (halved) after each scale, down to the floor."""
    anderson: bool = True
    """Anderson acceleration of the fixed-point iteration, with FRICP's energy safeguard."""
    anderson_m: int = 5
    """Anderson window: how many previous iterates are combined."""
    max_correspondence_distance: float = 5.0
    """Metres. Final pairs are mutual nearest neighbours closer than this (not used while fitting:
    the Welsch weights discount outliers instead)."""

    def __post_init__(self) -> None:
        check_count(self, "max_iterations", 1)
        check_count(self, "anderson_m", 1)
        check_positive(self, "tolerance", "nu_begin_k", "nu_end_k", "max_correspondence_distance")
        check_at_most(self, {"max_iterations": 10_000, "anderson_m": 20, "max_correspondence_distance": 100.0})
        if not isinstance(self.nu_alpha, (int, float)) or not 0.0 < self.nu_alpha < 1.0:
            raise ValueError(f"RICPParams.nu_alpha must lie strictly between 0 and 1, got {self.nu_alpha!r}")
        if not isinstance(self.anderson, bool):
            raise ValueError(f"RICPParams.anderson must be a bool, got {self.anderson!r}")


def match_ricp(ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray,
               params: RICPParams | None = None) -> MatchResult:
    """Associate boxes and refine the CAV->ego transform by robust ICP on the box centres.

    Each round re-finds the closest ego centre ``p_i(j)`` of every CAV centre ``q_j`` under ``T`` and
    solves the weighted Procrustes problem ``min sum_j w_j ||p_i(j) - T q_j||^2`` with Welsch weights
    ``w_j = exp(-r_j^2 / (2 nu^2))``, ``r_j = ||p_i(j) - T q_j||``. nu starts at ``nu_begin_k`` times the
    median initial residual and is multiplied by ``nu_alpha`` after each converged scale down to the
    floor ``nu_end_k * median neighbour spacing``. The matched pairs are the mutual nearest neighbours
    within ``max_correspondence_distance`` under the final ``T``. Headings and sizes are not used.
    """
    return closest_point_match(ego_boxes, cav_boxes, init, check_params(params, RICPParams), ricp_transform)


def ricp_transform(ego_xy: np.ndarray, cav_xy: np.ndarray, init: np.ndarray, params: RICPParams) -> np.ndarray:
    """The robust ICP iterate after the last Welsch scale; ``init`` when fewer than 2 centres each side."""
    if len(ego_xy) < 2 or len(cav_xy) < 2:
        return init
    tree = cKDTree(ego_xy)
    nu_floor = max(params.nu_end_k * neighbour_spacing(tree, ego_xy), 1e-6)
    residuals, _ = tree.query(se2.apply_points(init, cav_xy))
    nu = max(params.nu_begin_k * float(np.median(residuals)), nu_floor)
    T = init
    while True:
        T = fit_at_scale(tree, ego_xy, cav_xy, T, nu, params)
        if nu <= nu_floor:
            return T
        nu = max(nu * params.nu_alpha, nu_floor)


def neighbour_spacing(tree: cKDTree, xy: np.ndarray) -> float:
    """Median over points of the median distance to their (up to) 6 nearest neighbours (FRICP)."""
    k = min(_SCALE_NEIGHBOURS, len(xy))
    dist, _ = tree.query(xy, k=k)
    return float(np.median(np.median(dist[:, 1:], axis=1)))


def welsch_weights(residuals: np.ndarray, nu: float) -> np.ndarray:
    """Welsch weights ``exp(-r^2 / (2 nu^2))``."""
    return np.exp(-(residuals**2) / (2.0 * nu**2))


def welsch_energy(residuals: np.ndarray, nu: float) -> float:
    """Welsch energy ``sum 1 - exp(-r^2 / (2 nu^2))`` (up to the constant factor)."""
    return float(np.sum(1.0 - welsch_weights(residuals, nu)))


def fit_at_scale(tree: cKDTree, ego_xy: np.ndarray, cav_xy: np.ndarray, T: np.ndarray, nu: float,
                 params: RICPParams) -> np.ndarray:
    """Reweighted closest-point fits at one Welsch scale ``nu`` until the transform settles.

    With Anderson acceleration (FRICP's ``point_to_point``), each fit ``G(T)`` is extrapolated from the
    last ``anderson_m`` iterates; an accelerated iterate whose energy is not lower than the previous
    one is replaced by the plain fit.
    """
    chart = _Chart(T)
    accelerator = _Anderson(params.anderson_m, chart.coords(T)) if params.anderson else None
    residuals, nearest = tree.query(se2.apply_points(T, cav_xy))
    T_plain, last_energy = T, math.inf
    for _ in range(params.max_iterations):
        if accelerator is not None:
            energy = welsch_energy(residuals, nu)
            if energy < last_energy:
                last_energy = energy
            else:
                T = T_plain
                accelerator.replace(chart.coords(T))
                residuals, nearest = tree.query(se2.apply_points(T, cav_xy))
                last_energy = welsch_energy(residuals, nu)
        weights = welsch_weights(residuals, nu)
        if np.count_nonzero(weights > _MIN_WEIGHT) < 2:
            break
        T_plain = weighted_procrustes(cav_xy, ego_xy[nearest], weights)
        T_next = T_plain if accelerator is None else chart.transform(accelerator.step(chart.coords(T_plain)))
        residuals, nearest = tree.query(se2.apply_points(T_next, cav_xy))
        converged = np.linalg.norm(T_next - T) < params.tolerance
        T = T_next
        if converged:
            break
    return T


class _Chart:
    """Coordinates ``(x, y, yaw)`` of ``T0^-1 T`` around a base transform ``T0``: smooth near ``T0``, so
    Anderson's linear combinations never cross the +-pi seam of the yaw."""

    def __init__(self, base: np.ndarray) -> None:
        self.base, self.base_inv = base, se2.inverse(base)

    def coords(self, T: np.ndarray) -> np.ndarray:
        D = self.base_inv @ T
        return np.array([D[0, 2], D[1, 2], se2.yaw_of(D)])

    def transform(self, u: np.ndarray) -> np.ndarray:
        return self.base @ se2.make(u[0], u[1], u[2])


class _Anderson:
    """Anderson acceleration (type II, window m) of a fixed-point map ``u -> g(u)`` (Walker and Ni,
    2011), with FRICP's interface: ``step(g)`` returns the next iterate, ``replace(u)`` swaps the current
    iterate for a safeguarded one and keeps the history."""

    def __init__(self, m: int, u0: np.ndarray) -> None:
        self.m = m
        self.u = u0
        self.prev_f: np.ndarray | None = None
        self.prev_g: np.ndarray | None = None
        self.dF: list[np.ndarray] = []
        self.dG: list[np.ndarray] = []

    def replace(self, u: np.ndarray) -> None:
        self.u = u

    def step(self, g: np.ndarray) -> np.ndarray:
        """``u+ = g - dG gamma`` with ``gamma = argmin ||f - dF gamma||``, ``f = g - u``."""
        f = g - self.u
        if self.prev_f is not None:
            self.dF = (self.dF + [f - self.prev_f])[-self.m:]
            self.dG = (self.dG + [g - self.prev_g])[-self.m:]
        self.prev_f, self.prev_g = f, g
        if self.dF:
            gamma = np.linalg.lstsq(np.column_stack(self.dF), f, rcond=None)[0]
            self.u = g - np.column_stack(self.dG) @ gamma
        else:
            self.u = g
        return self.u
