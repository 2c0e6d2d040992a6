"""What a tab's scene shows, read from the state the server sent the browser and the camera the browser
reported: where each label shows (viser draws labels in WebGL, not as page elements: a label's box is
where the camera puts its anchor, as wide and tall as ``framing.label_spot`` takes its text, to the
right of its anchor or, anchored ``top-right``, to its left), how large the boxes show, and the page
boxes of the panels floating over the canvas."""
from __future__ import annotations

import numpy as np

from app.scene import framing
from app.scene.deciding import corners
from support import browser as ui
from support import pixels

Box = tuple[float, float, float, float]
"""(left, top, right, bottom) page pixels."""


def label_boxes(tab, names=None, view=None) -> dict[str, Box]:
    """The boxes of the visible labels of the tab's scene (``view``: of that ``SceneView``; ``names``:
    those only)."""
    view = view or tab.stage.view
    camera, px = tab.client.camera, view.label_px
    boxes = {}
    for name, handle in list(view.labels.items()):
        if handle.visible and (names is None or names(name)):
            spot = framing.label_spot(handle.text, *handle.position[:2], px)
            u, v = pixels.project(camera, np.array([handle.position]))[0]
            u -= spot.width if handle.anchor == "top-right" else 0.0
            boxes[name] = (u, v, u + spot.width, v + spot.height)
    return boxes


def meets(a: Box, b: Box) -> bool:
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def overprinted(tab, view=None) -> list[tuple[str, str]]:
    """Pairs of visible labels whose boxes overlap."""
    boxes = label_boxes(tab, view=view)
    names = sorted(boxes)
    return [(a, b) for k, a in enumerate(names) for b in names[:k] if meets(boxes[a], boxes[b])]


def floating_panels(page) -> list[Box]:
    """The page boxes of the panels floating over the scene (the key numbers, a caption)."""
    return [(box["x"], box["y"], box["x"] + box["width"], box["y"] + box["height"])
            for window in page.locator("[data-floating-window]").all() if window.is_visible()
            and (box := window.bounding_box())]


def canvas_box(page) -> Box:
    canvas = ui.scene_canvas(page)
    return canvas["x"], canvas["y"], canvas["x"] + canvas["width"], canvas["y"] + canvas["height"]


def on_screen(points, tab, page) -> np.ndarray:
    """(N,) whether each ground point (N, 2), or point (N, 3), shows on the canvas and under no floating panel."""
    points = np.asarray(points, float)
    if not (points.ndim == 2 and points.shape[1] == 3):
        points = np.c_[points.reshape(-1, 2), np.zeros(points.size // 2)]
    where = pixels.project(tab.client.camera, points)
    left, top, right, bottom = canvas_box(page)
    shown = (where[:, 0] >= left) & (where[:, 0] <= right) & (where[:, 1] >= top) & (where[:, 1] <= bottom)
    for panel in floating_panels(page):
        shown &= ~((where[:, 0] > panel[0]) & (where[:, 0] < panel[2]) & (where[:, 1] > panel[1])
                   & (where[:, 1] < panel[3]))
    return shown


def cars(drawing) -> np.ndarray:
    """(N, 3) the corners of the ego's and every CAV's car as drawn (not the CAV before calibration)."""
    return np.concatenate([mesh.vertices for key, mesh in drawing.meshes.items()
                           if key == "ego_vehicle" or (key.startswith("cav_vehicle") and "before" not in key)])


def box_pixels(tab, page) -> float:
    """Square page pixels the ego's boxes cover on the canvas (those whose centre shows on it)."""
    boxes, _ = tab.last_drawing.objects["ego"]
    where = pixels.project(tab.client.camera, np.c_[corners(boxes), np.zeros(4 * len(boxes))]).reshape(-1, 4, 2)
    x, y = where[..., 0], where[..., 1]
    area = 0.5 * np.abs((x * np.roll(y, -1, 1) - np.roll(x, -1, 1) * y).sum(1))
    left, top, right, bottom = canvas_box(page)
    middle = where.mean(axis=1)
    inside = (middle[:, 0] >= left) & (middle[:, 0] <= right) & (middle[:, 1] >= top) & (middle[:, 1] <= bottom)
    return float(area[inside].sum())


def settled(page, tab) -> None:
    """Wait until the browser has reported the canvas's size and the camera the app last sent."""
    camera = tab.client.camera
    ui.wait_until(lambda: camera.image_width == round(ui.scene_canvas(page)["width"]) and tab.stage.camera.arrived, 120)
