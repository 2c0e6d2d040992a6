"""The walkthrough's geometry, in the ego frame: the boxes, pair lines, context vectors drawn in
one object's frame, and the Welsch weights as line widths. Everything lies flat in the main scene's
layers (``scene.planes``): the boxes as the same footprints the main scene draws, the lines in the
plane of its match lines, so that stepping into the walkthrough leaves every box where it was."""
from __future__ import annotations

import numpy as np

from cbm import se2

from ..scene import geometry, planes
from ..scene.cavs import SLIM
from ..scene.colours import CAV_BOXES, CAV_VEHICLE, EGO_BOXES, EGO_VEHICLE
from ..scene.drawing import Lines, Mesh, no_lines
from ..scene.inspector import band_segments, region_segments

CAV_LABEL = "cav_agent"
WEIGHT_CLASSES = ((0.75, 7.0), (0.5, 4.5), (0.25, 2.5), (0.0, 1.0))
"""(least Welsch weight, line width) of each class of pairs drawn in the robust fit's step."""


def ego_mesh(boxes: np.ndarray) -> Mesh:
    """The ego's boxes as the main scene draws them: footprints on the ego's layer."""
    return Mesh(*geometry.footprint_mesh(boxes, planes.EGO), EGO_BOXES)


def cav_mesh(boxes: np.ndarray) -> Mesh:
    """The CAV's boxes in the CAV's own frame (the node is placed by a pose) as the main scene draws
    the first CAV's: footprints narrowed on the same centre (``cavs.SLIM``) on its layer, so a matched
    pair shows both colours."""
    slim = boxes.copy()
    slim[:, 3:5] *= SLIM[0]
    return Mesh(*geometry.footprint_mesh(slim, planes.cav(1)), CAV_BOXES)


def agent_meshes() -> dict[str, Mesh]:
    """The ego's vehicle at the scene's origin and the CAV's at its own (its node is placed by a
    pose), in the main scene's colours: every step shows who sees what."""
    body = geometry.vehicle_mesh([np.eye(3)])
    return {"ego_vehicle": Mesh(*body, EGO_VEHICLE), "cav_vehicle": Mesh(*body, CAV_VEHICLE)}


def agent_labels(pose: np.ndarray) -> dict[str, tuple[str, tuple[float, float, float]]]:
    """"ego" over the ego, "CAV" over the CAV where ``pose`` stands it (``cav_label``)."""
    return {"ego_agent": ("ego", (0.0, 0.0, planes.LABELS)), CAV_LABEL: cav_label(pose)}


def cav_label(pose: np.ndarray) -> tuple[str, tuple[float, float, float]]:
    """The CAV's label where ``pose`` stands the CAV (an animation moves it with the vehicle)."""
    x, y = map(float, se2.translation_of(pose))
    return "CAV", (x, y, planes.LABELS)


def pair_segments(ego_xy: np.ndarray, cav_xy: np.ndarray, pairs: np.ndarray,
                  z: float = planes.LINES) -> np.ndarray:
    """(K, 2, 3) lines from each pair's ego centre to its CAV centre."""
    pairs = np.asarray(pairs, dtype=int).reshape(-1, 2)
    return geometry.segments(ego_xy[pairs[:, 0]], cav_xy[pairs[:, 1]], z)


def rays(origin: np.ndarray, targets: np.ndarray, z: float = planes.LINES) -> np.ndarray:
    """(N, 2, 3) lines from ``origin`` to each of ``targets``."""
    targets = np.asarray(targets, dtype=float).reshape(-1, 2)
    return geometry.segments(np.broadcast_to(origin, targets.shape), targets, z)


def to_scene(segments: np.ndarray, origin: np.ndarray, heading: float, z: float = planes.LINES) -> np.ndarray:
    """Segments given in an object's own frame (eq. 6-7), placed at ``origin`` turned by ``heading``."""
    c, s = np.cos(heading), np.sin(heading)
    out = np.array(segments, dtype=np.float32, copy=True)
    x, y = out[..., 0].copy(), out[..., 1].copy()
    out[..., 0], out[..., 1], out[..., 2] = origin[0] + c * x - s * y, origin[1] + s * x + c * y, z
    return out


def local_vectors(vectors: np.ndarray) -> np.ndarray:
    """(n, 2, 3) segments from an object's own origin to each context vector's tip."""
    vectors = np.asarray(vectors, dtype=float).reshape(-1, 2)
    return geometry.segments(np.zeros_like(vectors), vectors, 0.0)


def tolerance_region(vector: np.ndarray, sigma1_deg: float, sigma2: float) -> tuple[np.ndarray, np.ndarray]:
    """The sigma1 wedge and the sigma2 diamond (L1 ball) of eq. 8 around one context vector, in
    its object's frame (``cbm`` tests a vector of the other agent against both)."""
    vector = np.asarray(vector, dtype=float).reshape(1, 2)
    return band_segments(np.zeros(2), vector, sigma1_deg, sigma2), region_segments(np.zeros(2), vector, sigma2)


def weight_lines(segments: np.ndarray, weights: np.ndarray, color: tuple[int, int, int]) -> dict[str, Lines]:
    """One node per width class of ``WEIGHT_CLASSES`` (viser draws one width per node): each
    pair's line in the class of its weight."""
    weights = np.asarray(weights, dtype=float)
    nodes, upper = {}, np.inf
    for k, (least, width) in enumerate(WEIGHT_CLASSES, start=1):
        chosen = (weights >= least) & (weights < upper)
        nodes[f"weights_{k}"] = Lines(segments[chosen] if len(segments) else no_lines(), color, width)
        upper = least
    return nodes


def midpoints(segments: np.ndarray) -> np.ndarray:
    """(N, 3) middle of each segment, a little above it (where a label goes)."""
    if len(segments) == 0:
        return np.zeros((0, 3))
    middle = segments.mean(axis=1).astype(float)
    middle[:, 2] += 0.4
    return middle


def outlines(boxes: np.ndarray, z: float = planes.OUTLINES) -> np.ndarray:
    """(4N, 2, 3) footprint outlines of ``boxes`` (full size), on the outlines' layer unless ``z`` says."""
    return geometry.outline_segments(boxes, z)
