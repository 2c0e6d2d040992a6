"""Side-by-side timing of local matching's set-up pieces and of the whole ``cbm.match``, two checkouts.

On a machine shared with other work only ratios measured in the same session mean anything, so
this runs a worker process per checkout, alternately, ``--rounds`` times, each worker timing on
bench_match's trials (``trials_for``, same seeds; per trial the fastest of ``--repeats`` runs): the
context step (``cbm.reuse.prepare``: the signs and both agents' contexts), the heading groups'
grids (``build_grid``, one after another), the sorted blocks (``sorted_blocks`` of both agents) and
``match``. Prints, per scene and piece, the median over rounds (each round's value the median over
its trials) of both checkouts and their ratio.

    python bench/bench_pieces.py --base OTHER_CHECKOUT [--rounds 5] [--sizes 100 300] [--layouts street dense]
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parents[1]
PIECES = ("context", "grids", "blocks", "match")


def _worker(root: Path, size: int, layout: str, count: int, repeats: int) -> dict:
    """Median ms per piece over ``count`` trials (each the fastest of ``repeats`` runs: other work on
    the machine only slows a run down), with the ``cbm`` of ``root``."""
    sys.path[:0] = [str(HERE / "tests"), str(HERE / "bench")]
    from bench_match import trials_for

    sys.path.insert(0, str(root))
    import cbm
    from cbm import CBMParams, match
    from cbm.context import build_context, fold_heading, pair_signs
    from cbm.local_matching import build_grid, group_signs, heading_groups, sorted_blocks
    from cbm.reuse import prepare

    params = CBMParams()
    trials = trials_for(size, count, layout)
    match(trials[0].ego_boxes[:60], trials[0].cav_boxes[:60], trials[0].init, params)

    def pieces(trial) -> dict:
        """Each piece of one trial as a call."""
        ego_boxes, cav_boxes = trial.ego_boxes, trial.cav_boxes
        ego_heading, cav_heading = fold_heading(ego_boxes[:, 6]), fold_heading(cav_boxes[:, 6])
        signs = pair_signs(ego_heading, cav_heading, params.heading)
        ego, cav = build_context(ego_boxes[:, :2], ego_heading), build_context(cav_boxes[:, :2], cav_heading)
        groups = heading_groups(ego_heading, signs)
        return {
            "context": lambda: prepare(ego_boxes, cav_boxes, trial.init, params.heading),
            "grids": lambda: [build_grid(cav, group_signs(signs, group), params.sigma2) for group in groups],
            "blocks": lambda: (sorted_blocks(ego, len(ego_boxes)), sorted_blocks(cav, len(cav_boxes))),
            "match": lambda: match(ego_boxes, cav_boxes, trial.init, params),
        }

    times: dict[str, list[float]] = {piece: [] for piece in PIECES}
    for trial in trials:
        for piece, run in pieces(trial).items():
            times[piece].append(min(_seconds(run) for _ in range(repeats)))
    if not Path(cbm.__file__).resolve().is_relative_to(root):
        sys.exit(f"bench_pieces: error: cbm came from {cbm.__file__}, not from {root}")
    return {piece: 1000 * float(np.median(values)) for piece, values in times.items()}


def _seconds(run) -> float:
    """Wall seconds ``run()`` takes."""
    started = time.perf_counter()
    run()
    return time.perf_counter() - started


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--base", type=Path, required=True, help="the other checkout (the baseline)")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--trials", type=int, default=5)
    parser.add_argument("--repeats", type=int, default=3, help="runs per piece and trial (the fastest counts)")
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 300])
    parser.add_argument("--layouts", nargs="+", default=["street", "dense"])
    parser.add_argument("--worker", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        print(json.dumps(_worker(args.worker, args.sizes[0], args.layouts[0], args.trials, args.repeats)))
        return
    if not (args.base / "cbm").is_dir():
        sys.exit(f"bench_pieces: error: --base {args.base}: no cbm package there")
    print("| scene | piece | base ms | this ms | this/base |\n|---|---|---:|---:|---:|")
    for layout in args.layouts:
        for size in args.sizes:
            runs: dict[str, list[dict]] = {"base": [], "this": []}
            for _ in range(args.rounds):
                for name, root in (("base", args.base.resolve()), ("this", HERE)):
                    out = subprocess.run([sys.executable, __file__, "--base", str(args.base), "--worker", str(root),
                                          "--sizes", str(size), "--layouts", layout, "--trials", str(args.trials),
                                          "--repeats", str(args.repeats)],
                                         check=True, capture_output=True, text=True).stdout
                    runs[name].append(json.loads(out.splitlines()[-1]))
            for piece in PIECES:
                base, this = (float(np.median([run[piece] for run in runs[n]])) for n in ("base", "this"))
                print(f"| {layout} {size} | {piece} | {base:.2f} | {this:.2f} | {this / base:.2f} |", flush=True)


if __name__ == "__main__":
    main()
