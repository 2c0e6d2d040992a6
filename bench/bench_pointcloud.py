"""PCD reading: ``loaders.pointcloud.read_pcd`` on sweeps of DAIR-V2X's size (``x y z intensity``) in
each encoding, written with pypcd4; with ``--against FILE`` also an earlier ``pointcloud.py`` (the
numpy parser before pypcd4), read in alternation with the current one on the same files.

    python bench/bench_pointcloud.py [--points 70000] [--repeats 15] [--against old_pointcloud.py]

Prints the median milliseconds per read and, with ``--against``, the ratio current / earlier.
"""
from __future__ import annotations

import argparse
import importlib.util
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pypcd4

from loaders import errors, pointcloud

ENCODINGS = ("ascii", "binary", "binary_compressed")


def sweep(points: int, seed: int = 0) -> np.ndarray:
    """A LiDAR-like sweep: 64 rings, ground and clutter, float32 x y z intensity."""
    rng = np.random.default_rng(seed)
    ring = rng.integers(0, 64, points)
    angle = rng.uniform(-np.pi, np.pi, points)
    reach = rng.uniform(2.0, 80.0, points)
    return np.column_stack([reach * np.cos(angle), reach * np.sin(angle), -1.7 + 0.05 * ring,
                            rng.integers(0, 255, points)]).astype(np.float32)


def earlier_reader(path: Path):
    """``read_pcd`` of an earlier ``pointcloud.py`` (loaded as a module of the ``loaders`` package)."""
    spec = importlib.util.spec_from_file_location("loaders._earlier_pointcloud", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    module.errors = errors
    spec.loader.exec_module(module)
    return module.read_pcd


def timed(read, path: Path) -> float:
    start = time.perf_counter()
    read(path)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=70_000)
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--against", type=Path, default=None, help="an earlier loaders/pointcloud.py")
    args = parser.parse_args()
    earlier = earlier_reader(args.against) if args.against else None
    cloud = pypcd4.PointCloud.from_xyzi_points(sweep(args.points))
    print(f"{args.points} points, x y z intensity, median of {args.repeats} reads (ms)")
    print("| encoding | file MB | pypcd4 (now) | earlier | ratio |\n|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        for encoding in ENCODINGS:
            path = Path(folder) / f"{encoding}.pcd"
            cloud.save(path, encoding=pypcd4.Encoding(encoding))
            now, before = [], []
            for _ in range(args.repeats):
                now.append(timed(pointcloud.read_pcd, path))
                if earlier is not None:
                    try:
                        before.append(timed(earlier, path))
                    except errors.LoaderError:
                        pass
            ms = statistics.median(now) * 1e3
            old = statistics.median(before) * 1e3 if before else float("nan")
            cell = f"{old:.1f}" if before else "refused"
            ratio = f"{ms / old:.2f}" if before else "-"
            print(f"| {encoding} | {path.stat().st_size / 1e6:.2f} | {ms:.1f} | {cell} | {ratio} |")


if __name__ == "__main__":
    main()
