"""CBM time of a threshold edit in the app, and of a plain match, for two checkouts side by side.

Per dataset the app's own path is timed server-side: ``app.session.explorer.Explorer.compute`` on
the default preset's settings, first once (the frame's input is built and kept), then edits that
alternate a threshold between two values (``EDITS``), each edit's CBM time being
``result.timings["total"]`` as the page shows it. Then ``cbm.match`` (no reuse) on the bench scenes
of ``bench_match.py`` (SIND protocol, street and dense layouts), median per trial set. Each checkout
runs in a process of its own, the checkouts alternating round by round on the same machine (a loaded
machine shifts both alike), and the table gives the medians over the rounds and their ratio.

    python bench/bench_edit.py [--roots . ../baseline] [--rounds 5] [--datasets synthetic:300] [--sizes 100 300]
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve()
EDITS = {"sigma2": (2.5, 3.0), "sigma3": (0.8, 1.0), "sigma1": (9.0, 10.0)}
"""The threshold edits timed, each alternating between two values (the default preset's last)."""
PACKAGES = ("cbm", "loaders", "evaluation", "app")
"""The project's packages: a round must import every one of them from its own checkout."""
LAYOUTS = ("street", "dense")
"""The layouts of the plain matches (``bench_match.trials_for``)."""


def app_edits(dataset: str, edits: int) -> dict[str, float]:
    """Median CBM ms of ``edits`` edits per threshold through the app's ``Explorer`` on ``dataset``,
    and of its share that the join and the voting sets take."""
    import loaders
    from app.session.explorer import Explorer
    from app.session.presets import discover
    from app.session.settings import Settings

    explorer = Explorer(loaders.open(dataset))
    settings = discover()[0]["default"].apply(Settings())
    explorer.compute(settings)
    times = {}
    for name, values in EDITS.items():
        spent, joined = [], []
        for k in range(edits):
            timings = explorer.compute(settings.with_params("cbm", **{name: values[k % 2]})).result.timings
            spent.append(1000 * timings["total"])
            joined.append(1000 * (timings["local_matching"] + timings.get("voting_sets", 0.0)))
        times[f"{dataset} {name} edit"] = statistics.median(spent)
        times[f"{dataset} {name} edit: local matching + voting sets"] = statistics.median(joined)
    return times


def plain_matches(sizes: list[int], trials: int) -> dict[str, float]:
    """Median ms of ``cbm.match`` without reuse on both layouts at each of ``sizes`` objects per agent
    (``trials`` trials each), and
    of its local matching (the join and what it lists; ``MatchResult.timings``)."""
    from bench_match import trials_for

    from cbm import CBMParams, match

    times = {}
    for layout, size in ((layout, size) for size in sizes for layout in LAYOUTS):
        spent, joined = [], []
        for trial in trials_for(size, trials, layout):
            started = time.perf_counter()
            result = match(trial.ego_boxes, trial.cav_boxes, trial.init, CBMParams())
            spent.append(1000 * (time.perf_counter() - started))
            joined.append(1000 * result.timings["local_matching"])
        times[f"match {layout} {size}"] = statistics.median(spent)
        times[f"match {layout} {size}: local matching"] = statistics.median(joined)
    return times


def one_round(args: argparse.Namespace) -> dict[str, float]:
    """Every measure once, in this process (its checkout is the first entry of ``sys.path``)."""
    from cbm.warmup import warm_up

    warm_up()
    times = {}
    for dataset in args.datasets:
        times.update(app_edits(dataset, args.edits))
    times.update(plain_matches(args.sizes, args.trials))
    mixed = [name for name, module in list(sys.modules.items())
             if name.split(".")[0] in PACKAGES and Path.cwd() not in Path(module.__file__).resolve().parents]
    if mixed:
        raise SystemExit(f"bench_edit: {mixed[0]} was imported from another checkout than {Path.cwd()}")
    return times


def run_round(root: Path, args: argparse.Namespace) -> dict[str, float]:
    """One round measured in a process whose packages (and ``bench_match``) are ``root``'s."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(root), str(root / "tests"), str(root / "bench")]))
    command = [sys.executable, str(HERE), "--one", "--edits", str(args.edits), "--trials", str(args.trials),
               "--sizes", *map(str, args.sizes), "--datasets", *args.datasets]
    out = subprocess.run(command, cwd=root, env=env, capture_output=True, text=True)
    if out.returncode != 0:
        last = (out.stderr.strip().splitlines() or [f"exit status {out.returncode}"])[-1]
        raise SystemExit(f"bench_edit: the round in {root} failed: {last}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--roots", nargs="+", type=Path, default=[HERE.parents[1]],
                        help="checkouts to compare (the first is 'ours', the ratio is ours / the last)")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--edits", type=int, default=10)
    parser.add_argument("--trials", type=int, default=5)
    parser.add_argument("--datasets", nargs="*", default=["synthetic:300"])
    parser.add_argument("--sizes", type=int, nargs="*", default=[100, 300],
                        help="objects per agent of the plain matches")
    parser.add_argument("--one", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        if sys.path[0] == str(HERE.parent):
            del sys.path[0]  # the script's own bench/: the round's (on PYTHONPATH) is used instead
        print(json.dumps(one_round(args)))
        return 0
    roots = [root.resolve() for root in args.roots]
    for root in roots:
        if not (root / "cbm" / "pipeline.py").is_file():
            parser.error(f"--roots: {root} is not a checkout of this project (no cbm/pipeline.py)")
    rounds: list[list[dict[str, float]]] = [[] for _ in roots]
    for _ in range(args.rounds):
        for k, root in enumerate(roots):
            rounds[k].append(run_round(root, args))
    print(table(roots, rounds))
    return 0


def table(roots: list[Path], rounds: list[list[dict[str, float]]]) -> str:
    """Medians over the rounds (ms) per measure and checkout, and the first checkout's / the last's."""
    names = [root.name for root in roots]
    lines = [f"| measure | {' | '.join(f'{name} ms' for name in names)} | ratio |",
             "|---|" + "---:|" * (len(roots) + 1)]
    for measure in rounds[0][0]:
        medians = [statistics.median(r[measure] for r in per_root) for per_root in rounds]
        cells = " | ".join(f"{m:.1f}" for m in medians)
        lines.append(f"| {measure} | {cells} | {medians[0] / medians[-1]:.2f} |")
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
