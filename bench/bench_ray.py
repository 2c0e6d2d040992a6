"""A sweep over the shipped Argoverse 2 scene on the local process pool and on a local Ray instance.

Both run the same sweep (every 2nd frame, CBM and ICP, eta 0.4 and 0.8, seed 0) with 2 workers and
must give the same rows; each time covers the whole run, Ray's start-up and shutdown included.
Prints both times and the ratio Ray / pool (target: at most 1.5). Run: python bench/bench_ray.py
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path
from time import perf_counter

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from evaluation.run import load_source  # noqa: E402
from evaluation.sweep import Sweep, run  # noqa: E402

TARGET_RATIO = 1.5


def timed(sweep: Sweep, frames: list, workers: int, ray: str | None) -> tuple[float, list[dict]]:
    """Seconds the sweep takes and its rows without the runtime column."""
    start = perf_counter()
    rows = run(sweep, frames, workers=workers, ray=ray)
    return perf_counter() - start, [{k: v for k, v in row.items() if k != "runtime_s"} for row in rows]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--stride", type=int, default=2, help="every STRIDE-th frame (default: 2)")
    args = parser.parse_args()
    frames = load_source("argoverse2", "sind", frames=lambda n: range(0, n, args.stride)).inputs
    sweep = Sweep(methods=("cbm", "icp"), grid={"eta": (0.4, 0.8)}, seed=0)
    pool_s, pool_rows = timed(sweep, frames, args.workers, None)
    ray_s, ray_rows = timed(sweep, frames, args.workers, "local")
    assert ray_rows == pool_rows, "Ray and the process pool gave different rows"
    ratio = ray_s / pool_s
    print(f"sweep: {len(frames)} frames x 2 eta x (cbm, icp) = {len(pool_rows)} rows, {args.workers} workers")
    print(f"local process pool: {pool_s:6.1f} s")
    print(f"local Ray instance: {ray_s:6.1f} s (start-up included)")
    verdict = "met" if ratio <= TARGET_RATIO else "NOT met"
    print(f"ratio Ray / pool:   {ratio:6.2f} (target <= {TARGET_RATIO}): {verdict}")


if __name__ == "__main__":
    main()
