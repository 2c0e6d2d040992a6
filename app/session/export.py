"""What a tab can download, as bytes: the per-frame metrics of its last sequence run (CSV,
Parquet) and its current settings as a preset file (the screenshot is taken by ``panels.explore``)."""
from __future__ import annotations

import io
from collections.abc import Sequence
from typing import Any

import polars as pl
import tomli_w

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
