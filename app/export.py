"""What a tab can download: the per-frame metrics of its last sequence run (CSV, Parquet), its
current settings as a preset file, and a screenshot of its view."""
from __future__ import annotations

import io
from collections.abc import Sequence
from typing import Any

import numpy as np
import polars as pl
import tomli_w
import viser
from PIL import Image

from .settings import Settings, to_preset


def rows_frame(rows: Sequence[dict[str, Any]]) -> pl.DataFrame:
    """The rows as a table, columns in the sweep's order, every row read for the schema."""
    return pl.DataFrame(list(rows), infer_schema_length=None)


def metrics_csv(rows: Sequence[dict[str, Any]]) -> bytes:
    return rows_frame(rows).write_csv().encode("utf-8")


def metrics_parquet(rows: Sequence[dict[str, Any]]) -> bytes:
    out = io.BytesIO()
    rows_frame(rows).write_parquet(out)
    return out.getvalue()


def preset_toml(settings: Settings, dataset: str) -> bytes:
    """The settings as a preset file (``app.presets`` reads it back; frame and CAV left out)."""
    description = f"Exported from CBM Explorer ({dataset}, frame {settings.frame})."
    return tomli_w.dumps({"description": description, **to_preset(settings)}).encode("utf-8")


def png(image: np.ndarray) -> bytes:
    """An (H, W, 3 or 4) uint8 image as PNG bytes."""
    out = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(image)).save(out, format="PNG")
    return out.getvalue()


def screenshot(client: viser.ClientHandle, timeout: float = 20.0) -> bytes:
    """A render of the tab's current view from its own camera at the view's size, as PNG bytes
    (blocks until the browser answers; run it off the GUI threads)."""
    camera = client.camera
    width, height = camera.image_width or 1280, camera.image_height or 720
    return png(client.get_render(height, width, transport_format="png", timeout=timeout))
