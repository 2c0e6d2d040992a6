"""What the app offers on the dataset it serves: a choice that cannot work here (LiDAR points on a
dataset without point clouds, the dataset's own localization on one that reports no poses, the
joint pose graph with a single CAV) is not offered, and the page says why. Setting fewer CAVs than
the chosen method needs switches the method to the one it builds on, and says so (``adapted``)."""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from cbm.methods import METHODS
from loaders import Sequence

from .settings import Settings

GRAPH_CAVS = 2
"""CAVs the joint pose graph needs: it ties each CAV's pose to the others'."""


@dataclass(frozen=True)
class Offers:
    """Why each dataset-dependent choice is not offered (None: it is)."""

    points: str | None = None
    """Why the View tab's LiDAR points are unavailable."""
    reported_poses: str | None = None
    """Why localization ``dataset`` is unavailable."""
    scores: str | None = None
    """Why the Scenario tab's score threshold has nothing to drop (no detector's boxes with scores)."""

    def pose_graph(self, cavs: int) -> str | None:
        """Why a method that takes the other CAVs (the pose graph) cannot run with ``cavs`` CAVs."""
        if cavs >= GRAPH_CAVS:
            return None
        return f"it calibrates several CAVs jointly: set CAVs to {GRAPH_CAVS} or more first"

    def adapted(self, before: Settings, after: Settings) -> tuple[Settings, str | None]:
        """``after``, its method switched to the one whose parameters it shares (the pose graph: CBM)
        when the CAV count changed to fewer than the method needs; and the switch in words (None:
        nothing switched)."""
        method = METHODS[after.method]
        if after.cavs == before.cavs or not method.takes_peers or self.pose_graph(after.cavs) is None:
            return after, None
        fallback = METHODS[method.params_key]
        words = (f"{method.label} needs {GRAPH_CAVS} CAVs or more, so with {after.cavs} CAV the method is now "
                 f"{fallback.label}, with the same thresholds. Set CAVs to {GRAPH_CAVS} or more to choose "
                 f"{method.label} again (Method tab).")
        return dataclasses.replace(after, method=fallback.name), words

    def refusal(self, settings: Settings) -> str | None:
        """Why ``settings`` cannot be computed on this dataset, in one sentence; None when they can."""
        if settings.scenario.localization == "dataset" and self.reported_poses:
            return f"localization 'dataset' is not offered: {self.reported_poses}"
        method = METHODS[settings.method]
        if method.offline:
            return f"{method.label} answers once every frame is in: it runs over a whole recording, not frame by frame"
        why = self.pose_graph(settings.cavs) if method.takes_peers else None
        return None if why is None else f"{method.label} is not offered with {settings.cavs} CAV: {why}"


def offers_of(sequence: Sequence) -> Offers:
    """What ``sequence`` can show and compute."""
    points = None if sequence.point_clouds else "this dataset ships no LiDAR points (OPV2V-family data with .pcd " \
                                                "sweeps do)"
    poses = None if sequence.predicted_poses else "this dataset reports no noisy CAV poses of its own " \
                                                  "(OPV2V-family releases do)"
    scored = any(boxes.scores is not None for agents in sequence.detections.values() for boxes in agents.values())
    scores = None if scored else "no detector's boxes with scores here (start the app " \
                                 "with --detections and a detector's output that scores its boxes)"
    return Offers(points, poses, scores)
