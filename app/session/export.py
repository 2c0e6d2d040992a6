"""What a tab can download, as bytes: the per-frame metrics of its last sequence run (CSV,
Parquet), its current settings as a preset file, and a screenshot composed with the control panel's
key content (the render itself is taken by ``panels.explore``: the server cannot capture the page, so
the panel's metrics text is drawn beside the render with Pillow). The render comes with a
transparent background; the screenshot lays it on the page's background of the tab's theme."""
from __future__ import annotations

import io
import re
import textwrap
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import polars as pl
import tomli_w
from PIL import Image, ImageDraw, ImageFont

from .settings import Settings, to_preset


def slug(name: str) -> str:
    """A dataset's name as a file name part."""
    return re.sub(r"[^A-Za-z0-9]+", "-", name).strip("-")[:40]


def png(image: np.ndarray) -> bytes:
    """An (H, W, 3 or 4) uint8 image as PNG bytes."""
    out = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(image)).save(out, format="PNG")
    return out.getvalue()


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


FONT_FILES = ("/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
              "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf")
"""Fonts with Greek letters and degree signs, when the system has one (else Pillow's own)."""
PANEL_WIDTH = 420
WRAP = 50
"""Characters per line of the panel's text."""
PANEL_TITLE = "CBM Explorer — control panel"
BACKGROUND = {False: (255, 255, 255), True: (20, 20, 20)}
"""The scene's background in the light and the dark theme."""
PANEL_COLOURS = {False: ((255, 255, 255), (30, 30, 30), (200, 200, 200)),
                 True: ((37, 38, 43), (230, 230, 230), (70, 70, 70))}
"""The drawn panel's background, text and border in each theme."""


def panel_lines(markdown: str) -> list[str]:
    """The metrics panel's markdown as plain lines of at most ``WRAP`` characters: a table row
    ``| a | b |`` reads ``a: b``; emphasis, code marks and table rules go."""
    lines = []
    for raw in markdown.splitlines():
        if re.fullmatch(r"\|?[\s|:-]*\|?", raw) and "|" in raw:
            continue
        cells = [c.strip() for c in raw.strip().strip("|").split("|")] if raw.lstrip().startswith("|") else None
        text = ": ".join(c for c in cells if c) if cells else raw
        lines += textwrap.wrap(re.sub(r"[*`]", "", text).strip(), WRAP, subsequent_indent="  ") or [""]
    return lines


def _font(size: int) -> ImageFont.FreeTypeFont | ImageFont.ImageFont:
    for path in FONT_FILES:
        if Path(path).exists():
            return ImageFont.truetype(path, size)
    return ImageFont.load_default(size=size)


def opaque(render: np.ndarray, dark: bool = False) -> np.ndarray:
    """The (H, W, 3|4) ``render`` laid on the scene's background of the theme: (H, W, 3) uint8 (an
    RGBA render's transparent background would otherwise read black)."""
    if render.shape[-1] == 3:
        return np.ascontiguousarray(render)
    alpha = render[..., 3:4].astype(np.float32) / 255.0
    background = np.array(BACKGROUND[dark], np.float32)
    return np.round(render[..., :3] * alpha + background * (1.0 - alpha)).astype(np.uint8)


def with_panel(render: np.ndarray, markdown: str, size: int = 15, dark: bool = False) -> np.ndarray:
    """The (H, W, 3|4) ``render`` on the theme's background with a panel on its right holding the
    title and ``panel_lines(markdown)``, as the page shows them side by side, in the colours of the
    theme; (H', W + PANEL_WIDTH, 3) uint8."""
    lines, font, title = panel_lines(markdown), _font(size), _font(size + 3)
    fill, ink, border = PANEL_COLOURS[dark]
    step = size + 6
    height = max(render.shape[0], 2 * step + step * len(lines) + 16)
    canvas = Image.new("RGB", (render.shape[1] + PANEL_WIDTH, height), BACKGROUND[dark])
    canvas.paste(Image.fromarray(opaque(render, dark)), (0, 0))
    draw = ImageDraw.Draw(canvas)
    left = render.shape[1]
    draw.rectangle([(left, 0), (left + PANEL_WIDTH, height)], fill=fill)
    draw.line([(left, 0), (left, height)], fill=border, width=2)
    draw.text((left + 14, 12), PANEL_TITLE, fill=ink, font=title)
    for k, line in enumerate(lines):
        draw.text((left + 14, 12 + 2 * step + k * step), line, fill=ink, font=font)
    return np.asarray(canvas)
