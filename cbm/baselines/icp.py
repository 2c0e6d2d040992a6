"""ICP baseline: point-to-point Iterative Closest Point (Besl and McKay, 1992) on box centres."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from .. import se2
from ..estimate import weighted_procrustes
from ..inputs import check_at_most, check_positive
from ..result import MatchResult
from ._common import check_count, check_params, closest_point_match


@dataclass(frozen=True)
class ICPParams:
    """Parameters of the ICP baseline (the CBM paper, sec. IV, gives none).

    ``max_iterations`` and ``tolerance`` are the defaults of the Fast-and-Robust-ICP code (Zhang et al.,
    2022: ``max_icp = 100``, ``stop = 1e-5``) so that ICP and RICP stop alike.
    """

    max_iterations: int = 100
    """Most closest-point / fit rounds."""
    tolerance: float = 1e-5
    """Stop when the Frobenius norm of the change of the (3, 3) transform falls below this."""
    max_correspondence_distance: float = 5.0
    """Metres. A CAV centre farther than this from its closest ego centre takes no part in the fit,
    and the final mutual nearest neighbours must be closer than this."""

    def __post_init__(self) -> None:
        check_count(self, "max_iterations", 1)
        check_positive(self, "tolerance", "max_correspondence_distance")
        check_at_most(self, {"max_iterations": 10_000, "max_correspondence_distance": 100.0})


def match_icp(ego_boxes: np.ndarray, cav_boxes: np.ndarray, init: np.ndarray,
              params: ICPParams | None = None) -> MatchResult:
    """Associate boxes and refine the CAV->ego transform by ICP on the box centres.

    From ``T = init``: each CAV centre ``q_j`` takes its closest ego centre ``p_i(j)`` under ``T``;
    pairs within ``max_correspondence_distance`` give ``T = argmin sum ||p_i(j) - T q_j||^2``
    (Procrustes); repeat until ``||T_k - T_{k-1}||_F < tolerance`` or ``max_iterations``. The
    matched pairs are the mutual nearest neighbours within the gate under the final ``T``.
    Headings and sizes are not used.
    """
    return closest_point_match(ego_boxes, cav_boxes, init, check_params(params, ICPParams), icp_transform)


def icp_transform(ego_xy: np.ndarray, cav_xy: np.ndarray, init: np.ndarray, params: ICPParams) -> np.ndarray:
    """The ICP iterate at convergence; ``init`` unchanged when fewer than 2 centres fall within the gate."""
    if len(ego_xy) == 0 or len(cav_xy) < 2:
        return init
    tree = cKDTree(ego_xy)
    T = init
    for _ in range(params.max_iterations):
        dist, nearest = tree.query(se2.apply_points(T, cav_xy), distance_upper_bound=params.max_correspondence_distance)
        inside = np.isfinite(dist)
        if np.count_nonzero(inside) < 2:
            break
        T_next = weighted_procrustes(cav_xy[inside], ego_xy[nearest[inside]])
        converged = np.linalg.norm(T_next - T) < params.tolerance
        T = T_next
        if converged:
            break
    return T
