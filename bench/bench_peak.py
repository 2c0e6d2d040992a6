"""Peak memory of ``cbm.match`` at one scene, two checkouts in turns, each run in a fresh process.

A thread reads the process's resident size (``/proc/self/statm``) every ``EVERY`` seconds while
``match`` runs on the first trial of ``bench_match.py``'s scene (the kernels loaded beforehand on a
smaller call); per run it reports the resident size before the call, the sampled peak during it and the
process's ``ru_maxrss`` (what ``bench_match.py`` prints as the peak). The runs of the two checkouts
alternate, which goes first changing from round to round.

    python bench/bench_peak.py --against ../base [--scenes street:1000 dense:1000] [--rounds 2]
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
EVERY = 0.0005
"""Seconds between two reads of the resident size."""
OTHER_CACHE = Path(tempfile.gettempdir()) / "cbm-bench-peak-kernels"
"""Where the other checkout's kernels and bytecode are cached, never next to its sources."""
WARM = 200
"""Objects per agent of the call that loads the kernels first: enough to reach the parallel join."""


def resident_mb() -> float:
    """The process's resident size in MB (``/proc/self/statm``, second field, in pages)."""
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


class Sampler(threading.Thread):
    """The highest resident size seen until ``stop``."""

    def __init__(self) -> None:
        super().__init__(daemon=True)
        self.peak, self.running = resident_mb(), True

    def run(self) -> None:
        while self.running:
            self.peak = max(self.peak, resident_mb())
            time.sleep(EVERY)

    def stop(self) -> float:
        self.running = False
        self.join()
        return max(self.peak, resident_mb())


def measure(checkout: Path, scene: str) -> dict:
    """One match of ``scene``'s first trial by ``checkout``'s ``cbm`` (imported before ``bench_match``,
    which puts this checkout first on the path): resident MB before, sampled peak during,
    ``ru_maxrss`` after, and the match's milliseconds."""
    sys.path.insert(0, str(checkout))
    import cbm
    from cbm import match

    sys.path.append(str(ROOT / "bench"))
    from bench_match import trials_for

    if Path(cbm.__file__).resolve().parents[1] != checkout.resolve():
        raise SystemExit(f"bench_peak: imported {cbm.__file__}, not {checkout}'s cbm")

    layout, size = scene.split(":")
    trial = trials_for(int(size), 1, layout)[0]
    match(trial.ego_boxes[:WARM], trial.cav_boxes[:WARM], trial.init)
    before = resident_mb()
    sampler = Sampler()
    sampler.start()
    started = time.perf_counter()
    match(trial.ego_boxes, trial.cav_boxes, trial.init)
    seconds = time.perf_counter() - started
    return dict(before=before, peak=sampler.stop(), maxrss=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
                ms=1000 * seconds)


def run_fresh(checkout: Path, scene: str, own: bool) -> dict:
    """``measure`` in a new process; the other checkout's caches go to ``OTHER_CACHE``."""
    env = dict(os.environ)
    if not own:
        env.update(NUMBA_CACHE_DIR=str(OTHER_CACHE / "numba"), PYTHONPYCACHEPREFIX=str(OTHER_CACHE / "pyc"))
    out = subprocess.run([sys.executable, __file__, "--one", scene, "--checkout", str(checkout)], env=env,
                         capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", type=Path, help="the other checkout (the baseline)")
    parser.add_argument("--scenes", nargs="+", default=["street:1000", "dense:1000"])
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--one", help=argparse.SUPPRESS)
    parser.add_argument("--checkout", type=Path, default=ROOT, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(measure(args.checkout, args.one)))
        return
    checkouts = {"this": ROOT} if args.against is None else {"base": args.against.resolve(), "this": ROOT}
    print("| scene | checkout | runs | resident before MB | sampled peak MB (+ match) | ru_maxrss MB | match ms |")
    print("|---|---|---:|---:|---:|---:|---:|")
    for scene in args.scenes:
        runs: dict[str, list[dict]] = {name: [] for name in checkouts}
        for round_ in range(args.rounds):
            for name in (list(checkouts) if round_ % 2 == 0 else list(checkouts)[::-1]):
                runs[name].append(run_fresh(checkouts[name], scene, checkouts[name] == ROOT))
        for name, found in runs.items():
            median = {key: float(np.median([r[key] for r in found])) for key in found[0]}
            print(f"| {scene} | {name} | {len(found)} | {median['before']:.0f} | {median['peak']:.0f} "
                  f"(+{median['peak'] - median['before']:.0f}) | {median['maxrss']:.0f} | {median['ms']:.0f} |",
                  flush=True)


if __name__ == "__main__":
    main()
