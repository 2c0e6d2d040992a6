"""Generic tables: CSV or Parquet with the canonical box columns plus ``frame``.

The schema is documented in ``loaders/README.md`` ("Generic table"). In short: required
``frame`` (integer), ``track_id``, ``x``, ``y``, ``length``, ``width``, ``yaw``; optional
``category`` (default ``"unknown"``), ``height`` (default 1.5 m), ``z`` (default ``height / 2``),
``timestamp`` (seconds; default ``frame / 10``) and ``agent``. A row with an ``agent`` says that
agent sees that object (per-agent detections); the object's box in the frame is its row without
an agent if there is one, else its first row. An agent whose id is also a ``track_id`` in the
frame gets that object's box as its pose.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import polars as pl

from .scene import AGENT_COLUMNS, OBJECT_COLUMNS, Sequence
from .tables import drop_unusable, read_arrow, read_csv, require_rows

SUFFIXES = (".csv", ".parquet", ".pq", ".feather", ".arrow", ".ipc")
REQUIRED = {"frame": pl.Int64, "track_id": pl.Utf8, "x": pl.Float64, "y": pl.Float64,
            "length": pl.Float64, "width": pl.Float64, "yaw": pl.Float64}
OPTIONAL = {"category": pl.Utf8, "z": pl.Float64, "height": pl.Float64, "timestamp": pl.Float64,
            "agent": pl.Utf8}
DEFAULT_HEIGHT = 1.5
DEFAULT_RATE = 10.0
EXPECTED = "a generic table (.csv / .parquet with a frame column)"
BROAD = True
"""Recognises any CSV, Parquet or Arrow file: tried after the loaders that recognise narrowly."""


def recognises(path: Path) -> bool:
    """Any CSV / Parquet / Arrow file (tried after the dataset-specific loaders)."""
    return path.is_file() and path.suffix.lower() in SUFFIXES


def load(path: str | Path) -> Sequence:
    """Load a generic CSV / Parquet / Arrow table of boxes."""
    path = Path(path)
    types = {**REQUIRED, **OPTIONAL}
    reader = read_csv if path.suffix.lower() == ".csv" else read_arrow
    rows = reader(path, types, optional=tuple(OPTIONAL))
    require_rows(path, rows)
    rows, dropped = drop_unusable(path, rows,
                                  [c for c in types if c in rows.columns and c not in ("agent", "category")])
    rows = _with_defaults(rows)
    frame_values = np.unique(rows["frame"].to_numpy())
    rows = rows.with_columns(pl.Series("frame", np.searchsorted(frame_values, rows["frame"].to_numpy())))
    objects = (rows.sort(pl.col("agent").is_not_null(), maintain_order=True)
               .unique(["frame", "track_id"], keep="first", maintain_order=True)
               .sort("frame", maintain_order=True))
    seen = rows.filter(pl.col("agent").is_not_null())
    timestamps = (rows.group_by("frame").agg(pl.col("timestamp").first()).sort("frame")["timestamp"].to_numpy())
    return Sequence(
        name=f"table/{path.name}",
        objects=objects.select("frame", *OBJECT_COLUMNS),
        frame_ids=[int(v) for v in frame_values],
        timestamps=timestamps,
        agents=_agents(objects, seen) if seen.height else None,
        visibility=(seen.select("frame", pl.col("agent").alias("agent_id"), "track_id")
                    .unique(maintain_order=True)) if seen.height else None,
        dropped_rows=dropped,
    )


def _with_defaults(rows: pl.DataFrame) -> pl.DataFrame:
    defaults = {
        "category": pl.lit("unknown"),
        "height": pl.lit(DEFAULT_HEIGHT),
        "agent": pl.lit(None, dtype=pl.Utf8),
        "timestamp": pl.col("frame").cast(pl.Float64) / DEFAULT_RATE,
    }
    rows = rows.with_columns([value.alias(name) for name, value in defaults.items() if name not in rows.columns])
    rows = rows.with_columns(
        pl.col("category").fill_null("unknown"),
        pl.when(pl.col("agent").str.len_chars() > 0).then(pl.col("agent")).alias("agent"),
    )
    if "z" not in rows.columns:
        rows = rows.with_columns((pl.col("height") / 2).alias("z"))
    return rows


def _agents(objects: pl.DataFrame, seen: pl.DataFrame) -> pl.DataFrame | None:
    """Poses of the agents that are also objects of their frame."""
    ids = seen.select("frame", pl.col("agent").alias("agent_id")).unique()
    agents = ids.join(objects, left_on=["frame", "agent_id"], right_on=["frame", "track_id"], how="inner")
    if not agents.height:
        return None
    return agents.select("frame", *AGENT_COLUMNS)
