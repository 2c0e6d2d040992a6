"""Loader timings: the shipped Argoverse 2 log (load + build every frame), a SinD-size vehicle
track file (about 1 million rows, generated here in the official 18-column format), and the
largest synthetic scene.

    python bench/bench_loaders.py [--rows 1000000]
"""
from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np
import polars as pl

import loaders
from loaders import sind


def best_of(repeats: int, run) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return min(times)


def all_frames(name_or_path) -> None:
    seq = loaders.open(name_or_path)
    for frame in seq:
        frame.objects, frame.boxes(), frame.agents


def write_sind_vehicles(path: Path, rows: int, seed: int = 0) -> None:
    """A SinD-like ``Veh_smoothed_tracks.csv``: 100 vehicles present in every frame."""
    rng = np.random.default_rng(seed)
    per_frame = 100
    frames = rows // per_frame
    frame_id = np.repeat(np.arange(frames), per_frame)
    track_id = np.tile(np.arange(per_frame), frames)
    heading = rng.uniform(-np.pi, np.pi, per_frame)[track_id]
    speed = rng.uniform(0, 12, per_frame)[track_id]
    t = frame_id * 0.1001001
    x = rng.uniform(-60, 60, per_frame)[track_id] + np.cos(heading) * speed * t % 120 - 60
    y = rng.uniform(-60, 60, per_frame)[track_id] + np.sin(heading) * speed * t % 120 - 60
    n = len(frame_id)
    table = pl.DataFrame({
        "track_id": track_id, "frame_id": frame_id, "timestamp_ms": frame_id * 100.1001,
        "agent_type": np.array(["car", "truck", "bus", "motorcycle"])[track_id % 4],
        "x": x, "y": y, "vx": np.cos(heading) * speed, "vy": np.sin(heading) * speed,
        "yaw_rad": heading, "heading_rad": heading,
        "length": rng.uniform(4, 5, per_frame)[track_id], "width": rng.uniform(1.7, 2.0, per_frame)[track_id],
        **{c: np.zeros(n) for c in ("ax", "ay", "v_lon", "v_lat", "a_lon", "a_lat")},
    })
    table.select(sind.VEHICLE_COLUMNS).write_csv(path)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rows", type=int, default=1_000_000)
    args = parser.parse_args()

    seconds = best_of(5, lambda: all_frames("argoverse2"))
    print(f"argoverse2 default log, load + all 156 frames: {seconds * 1000:.0f} ms (best of 5)")

    seconds = best_of(3, lambda: all_frames("synthetic:1000"))
    print(f"synthetic:1000, 50 frames, generate + all frames: {seconds * 1000:.0f} ms (best of 3)")

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / sind.VEHICLE_FILE
        write_sind_vehicles(path, args.rows)
        size = path.stat().st_size / 1e6
        seconds = best_of(2, lambda: loaders.open(path))
        seq = loaders.open(path)
        print(f"SinD vehicles, {args.rows:,} rows ({size:.0f} MB, {len(seq):,} frames): "
              f"load {seconds:.2f} s (best of 2)")


if __name__ == "__main__":
    main()
