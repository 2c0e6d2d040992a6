"""Reading the scene back from a browser's pixels: the page as an array, and where a point of the ego
frame shows on it (the tab's camera, as the browser reported it)."""
from __future__ import annotations

import io

import numpy as np
from PIL import Image

from support.browser import settled_screenshot


def screenshot(page) -> np.ndarray:
    """(H, W, 3) uint8 RGB of the page once it stands still."""
    return np.asarray(Image.open(io.BytesIO(settled_screenshot(page))).convert("RGB"))


def project(camera, points: np.ndarray) -> np.ndarray:
    """(N, 2) page pixels (x right, y down) of (N, 3) points seen by the viser ``camera`` (a
    three.js perspective camera: vertical field of view ``fov``, up +z)."""
    position, look_at = np.asarray(camera.position, float), np.asarray(camera.look_at, float)
    forward = (look_at - position) / np.linalg.norm(look_at - position)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    rel = np.asarray(points, float) - position
    depth = rel @ forward
    focal = camera.image_height / 2 / np.tan(camera.fov / 2)
    return np.stack([camera.image_width / 2 + focal * (rel @ right) / depth,
                     camera.image_height / 2 - focal * (rel @ up) / depth], axis=1)
