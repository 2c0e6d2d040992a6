"""A method's first frame on a fresh install: how long the tab's recompute takes, compile included.

Per checkout, in a process of its own with an empty numba cache, the app's kernels are made ready as
a server does (``app.session.kernels.prepare``: CBM's compiled in subprocesses, then, where the
checkout does so, the baselines'), the shipped scene's frame 0 is computed with CBM, and then each
method of ``--methods`` on the next frames, each timed as the tab's recompute (``Explorer.compute``).
Before each method's frame the run waits for whatever the checkout's kernels still prepare for it
(``Kernels.wait``), as a tab waits; that wait is printed apart: it runs off the request path, in a
subprocess, while the server answers other tabs. Prints one table, the checkouts side by side.

    python bench/bench_first_use.py [--roots . ../before] [--methods freealign v2xregpp]
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve()


def one_round(methods: list[str]) -> dict[str, float]:
    """Seconds: CBM ready, then per method the wait for its kernels and its first frame's recompute."""
    import loaders
    from app.session import kernels as kernels_module
    from app.session.explorer import Explorer
    from app.session.settings import Settings

    started = time.perf_counter()
    kernels = kernels_module.prepare()
    kernels.wait()
    measured = {"CBM's kernels ready after start": time.perf_counter() - started}
    explorer = Explorer(loaders.open("argoverse2"))
    explorer.compute(Settings())
    for frame, method in enumerate(methods, start=1):
        waited = time.perf_counter()
        if hasattr(kernels, "ready_for"):
            kernels.wait(method=method)
        measured[f"{method}: waiting for its kernels (off the request path)"] = time.perf_counter() - waited
        computing = time.perf_counter()
        explorer.compute(dataclasses.replace(Settings(), method=method, frame=frame))
        measured[f"{method}: its first frame's recompute"] = time.perf_counter() - computing
    return measured


def run_round(root: Path, methods: list[str]) -> dict[str, float]:
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, PYTHONPATH=str(root), NUMBA_CACHE_DIR=cache)
        out = subprocess.run([sys.executable, str(HERE), "--one", "--methods", *methods], cwd=root, env=env,
                             capture_output=True, text=True)
    if out.returncode != 0:
        last = (out.stderr.strip().splitlines() or [f"exit status {out.returncode}"])[-1]
        raise SystemExit(f"bench_first_use: the round in {root} failed: {last}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--roots", nargs="+", type=Path, default=[HERE.parents[1]])
    parser.add_argument("--methods", nargs="+", default=["freealign", "v2xregpp"])
    parser.add_argument("--one", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        if sys.path[0] == str(HERE.parent):
            del sys.path[0]
        print(json.dumps(one_round(args.methods)))
        return 0
    roots = [root.resolve() for root in args.roots]
    results = [run_round(root, args.methods) for root in roots]
    print(f"| measure | {' | '.join(f'{root.name} s' for root in roots)} |")
    print("|---|" + "---:|" * len(roots))
    for measure in results[0]:
        print(f"| {measure} | {' | '.join(f'{r[measure]:.2f}' for r in results)} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
