"""Per-step times of ``cbm.match`` (``MatchResult.timings``), two checkouts side by side.

On a machine others load too, only times taken together mean anything: the other checkout's
``cbm`` is imported into the same process under another name, and every trial runs in both,
alternating which goes first, round after round. Per step it prints the median over all runs of
each checkout, the median of the per-run ratios (other / this checkout: the load hits both runs
of a pair alike) and, for the total, the share of pairs where this checkout was faster.

    python bench/bench_steps.py --against ../base [--scenes street:100 street:300 dense:300] [--rounds 5]

Without ``--against`` it prints this checkout's medians only. The trials are ``bench_match.py``'s;
the pairs and transforms of both checkouts are compared on every run (a difference stops it).
"""
from __future__ import annotations

import argparse
import importlib.util
import sys
import tempfile
from pathlib import Path
from types import ModuleType

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests"), str(ROOT / "bench")]
STEPS = ("context", "local_matching", "consensus_selection", "estimate", "reassociate", "total")
"""The steps timed (a checkout that times the voting sets apart has them counted in local matching)."""
OTHER_CACHE = Path(tempfile.gettempdir()) / "cbm-bench-steps-kernels"
"""Where the other checkout's kernels are cached (compiled on the first run, loaded after)."""
ROUNDING = 1e-9
"""Largest difference of the two checkouts' transforms taken as rounding (``test_match_reference``)."""


def other_cbm(checkout: Path) -> ModuleType:
    """``checkout``'s ``cbm`` package, imported as ``cbm_other`` (its modules import each other
    relatively). Its kernels are cached in ``OTHER_CACHE``, never next to its sources: a kernel
    cached under the name ``cbm_other`` would not load where that checkout runs as ``cbm``."""
    import numba

    spec = importlib.util.spec_from_file_location("cbm_other", checkout / "cbm" / "__init__.py",
                                                  submodule_search_locations=[str(checkout / "cbm")])
    module = importlib.util.module_from_spec(spec)
    sys.modules["cbm_other"] = module
    own, numba.config.CACHE_DIR = numba.config.CACHE_DIR, str(OTHER_CACHE)
    try:
        spec.loader.exec_module(module)
    finally:
        numba.config.CACHE_DIR = own
    return module


def run(package: ModuleType, trial) -> tuple[dict[str, float], object]:
    """Milliseconds per step of one match of ``trial`` by ``package``, and its result."""
    result = package.match(trial.ego_boxes, trial.cav_boxes, trial.init, package.CBMParams())
    return {step: 1000 * result.timings.get(step, 0.0) for step in STEPS}, result


def same(a, b, scene: str) -> None:
    """Stops with a one-line message when two results' pairs or transforms differ."""
    if not np.array_equal(a.pairs, b.pairs) or np.abs(a.transform - b.transform).max() > ROUNDING:
        raise SystemExit(f"bench_steps: the checkouts' results differ on {scene}")


def measure(scene: str, packages: dict[str, ModuleType], rounds: int, trials: int) -> dict[str, dict[str, list]]:
    """Per checkout and step, the milliseconds of every run of every trial of ``scene`` (``layout:size``)."""
    from bench_match import trials_for

    layout, size = scene.split(":")
    found = trials_for(int(size), trials, layout)
    for package in packages.values():
        run(package, found[0])
    times = {name: {step: [] for step in STEPS} for name in packages}
    names = list(packages)
    for round_ in range(rounds):
        for k, trial in enumerate(found):
            results = {}
            for name in (names if (round_ + k) % 2 == 0 else names[::-1]):
                timings, results[name] = run(packages[name], trial)
                timings["local_matching"] += timings.pop("voting_sets", 0.0)
                for step in STEPS:
                    times[name][step].append(timings[step])
            if len(results) == 2:
                same(*results.values(), scene)
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", type=Path, help="the other checkout (the baseline)")
    parser.add_argument("--scenes", nargs="+", default=["street:100", "street:300", "dense:300"])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--trials", type=int, default=7)
    args = parser.parse_args()
    for scene in args.scenes:
        layout, _, size = scene.partition(":")
        if layout not in ("street", "dense") or not size.isdigit():
            print(f"bench_steps: --scenes {scene}: expected street:SIZE or dense:SIZE", file=sys.stderr)
            raise SystemExit(2)
    import cbm
    packages = {"this": cbm}
    if args.against is not None:
        if not (args.against / "cbm" / "__init__.py").is_file():
            print(f"bench_steps: --against {args.against}: no cbm/__init__.py there", file=sys.stderr)
            raise SystemExit(2)
        packages = {"base": other_cbm(args.against.resolve()), "this": cbm}
    for scene in args.scenes:
        times = measure(scene, packages, args.rounds, args.trials)
        print(f"{scene}: median ms of {args.rounds} rounds x {args.trials} trials"
              + (", per-run ratio base / this, alternating" if len(packages) == 2 else ""))
        print("| step | " + " | ".join(packages) + (" | base / this |" if len(packages) == 2 else " |"))
        print("|---|" + "---:|" * (len(packages) + (len(packages) == 2)))
        for step in STEPS:
            cells = [f"{np.median(times[name][step]):.2f}" for name in packages]
            if len(packages) == 2:
                base, this = np.array(times["base"][step]), np.array(times["this"][step])
                cells.append(f"{np.median(base / np.maximum(this, 1e-6)):.2f}"
                             + (f" (faster in {np.mean(this < base):.0%})" if step == "total" else ""))
            print(f"| {step} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
