"""Shared steps of the drone / track-file datasets (SinD, INTERACTION): frame indexing, default
heights, pedestrian footprints."""
from __future__ import annotations

import numpy as np
import polars as pl

PEDESTRIAN_FOOTPRINT = (0.6, 0.6)
"""Length and width given to pedestrians, which the track files record as points."""
PEDESTRIAN_MIN_SPEED = 0.2
"""Below this speed (m/s) a pedestrian's yaw is 0 instead of its walking direction."""
HEIGHTS = {"car": 1.6, "truck": 3.2, "bus": 3.2, "motorcycle": 1.5, "bicycle": 1.5,
           "tricycle": 1.7, "pedestrian": 1.7, "pedestrian/bicycle": 1.7}
DEFAULT_HEIGHT = 1.6
"""The track files have no heights: boxes get a typical height for their category and stand on
the ground (``z = height / 2``)."""


def with_heights(objects: pl.DataFrame) -> pl.DataFrame:
    """Add ``height`` (typical for the category) and ``z`` (half of it)."""
    height = (pl.col("category").str.to_lowercase()
              .replace_strict(HEIGHTS, default=DEFAULT_HEIGHT, return_dtype=pl.Float64))
    return objects.with_columns(height.alias("height")).with_columns((pl.col("height") / 2).alias("z"))


def pedestrian_boxes(peds: pl.DataFrame) -> pl.DataFrame:
    """Pedestrian points as boxes: the default footprint, yaw along the velocity."""
    speed = (pl.col("vx") ** 2 + pl.col("vy") ** 2).sqrt()
    return peds.with_columns(
        pl.lit(PEDESTRIAN_FOOTPRINT[0]).alias("length"),
        pl.lit(PEDESTRIAN_FOOTPRINT[1]).alias("width"),
        pl.when(speed >= PEDESTRIAN_MIN_SPEED).then(pl.arctan2("vy", "vx")).otherwise(0.0).alias("yaw"),
    )


def indexed_frames(parts: list[pl.DataFrame]) -> tuple[pl.DataFrame, np.ndarray, np.ndarray]:
    """Stack per-file boxes with ``frame_id`` and ``timestamp_ms``; return them with a 0-based
    ``frame`` index, the frame ids and the timestamps (seconds; the first row of each frame)."""
    stacked = pl.concat(parts, how="diagonal_relaxed")
    frames = (stacked.select("frame_id", "timestamp_ms")
              .unique("frame_id", keep="first", maintain_order=True).sort("frame_id"))
    ids = frames["frame_id"].to_numpy()
    stacked = stacked.with_columns(
        pl.Series("frame", np.searchsorted(ids, stacked["frame_id"].to_numpy())))
    return stacked, ids, frames["timestamp_ms"].to_numpy() / 1000.0
