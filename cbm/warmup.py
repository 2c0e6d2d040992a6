"""Compile CBM's numba kernels ahead of the first real call, into numba's on-disk cache.

``cbm.match`` runs numba kernels that are compiled on their first call (seconds) and cached on disk
(``cache=True``: next to the sources, or in ``NUMBA_CACHE_DIR``); later processes load them in a
fraction of a second. ``warm_up`` calls ``match`` on a small synthetic scene once per parameter
variant that reaches a kernel of its own, so that a caller's first real call compiles nothing.

    python -m cbm.warmup      # fill the cache; prints one line per variant, then the total seconds

Run it in a subprocess to fill the cache without holding the caller's interpreter lock (numba's
compiler is mostly Python), then call ``warm_up(VARIANTS[:1])`` in the caller to load the kernels.
The compiler runs on one core, so ``compile_side_by_side`` compiles the two halves of the kernels in
two processes at once: local matching's (``compile_matching``) and the selection's
(``compile_selection``); each finds the other's in the cache afterwards. The baselines' kernels
(FreeAlign's subgraph search; V2X-Reg++ runs on CBM's fitting kernels) are a part of their own
(``compile_baselines``), compiled after CBM's (``compile_side_by_side(parts=BASELINE_PARTS)``) and
loaded with ``load_kernels(baselines=True)``: CBM comes first, and a fresh install compiles them in about ten
seconds more.
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from importlib import import_module
from pathlib import Path

import numpy as np

from . import se2
from .engine import PairSets, Reuse, candidate_sets, filtered_sizes, select, tuning
from .engine.assignment import gated_assignment
from .engine.context import prepare
from .engine.counting import counts_and_votes
from .engine.filtered import filtering
from .engine.interpreted import kernels
from .engine.listing import closed_up, new_listing, writers
from .engine.rival import RivalSearch, runner_up
from .engine.selection import by_count_descending
from .engine.voting import voted_by_member
from .estimate import robust_fit
from .hypotheses import evidence, same_pose
from .params import CBMParams
from .pipeline import checked_inputs, match
from .sets import build_sets

VARIANTS: tuple[CBMParams, ...] = (
    CBMParams(),
    CBMParams(consensus_rule="paper"),
    CBMParams(consensus=False),
    CBMParams(heading="fold"),
    CBMParams(estimator="least_squares", refine=False),
)
"""The defaults first (what a first frame needs), then one change each: the consensus rule, the
consensus off, the heading handling, the released code's estimator without the re-association."""


def scene(n: int = 30, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(ego boxes, CAV boxes, init) of ``n`` co-visible cars seen by both agents, the CAV's pose
    off by 1 m, 1 m and 2 degrees: enough structure for every stage of ``match`` to run."""
    rng = np.random.default_rng(seed)
    boxes = np.zeros((n, 7))
    boxes[:, :2] = rng.uniform(-30.0, 30.0, (n, 2))
    boxes[:, 2:6] = (0.8, 4.5, 1.9, 1.6)
    boxes[:, 6] = rng.uniform(-np.pi, np.pi, n)
    truth = se2.make(5.0, -3.0, 0.3)
    cav = se2.apply_boxes(se2.inverse(truth), boxes)
    cav[:, :2] += rng.normal(0.0, 0.1, (n, 2))
    return boxes, cav, se2.make(1.0, 1.0, np.radians(2.0)) @ truth


def load_kernels(baselines: bool = False) -> float:
    """Load the kernels numba's cache holds into this process (compiling what it lacks) with one
    small match at the defaults (with ``baselines``: the baselines' instead, ``compile_baselines``);
    the seconds it took."""
    if not baselines:
        return warm_up(VARIANTS[:1])
    started = time.perf_counter()
    compile_baselines()
    return time.perf_counter() - started


def kernels_cached(baselines: bool = False) -> bool:
    """Whether numba's on-disk cache holds kernels of every module of CBM's that has some (with
    ``baselines``: of every baseline's module instead), compiled by this numba from these sources (a
    stale entry reads as none): then loading them takes a fraction of a second. (A module's inlined
    kernels, or the ones only a variant calls, may be missing.)"""
    if baselines:
        import_module(".baselines.freealign", __package__)
    found: dict[str, bool] = {}
    for _, _, dispatcher in kernels():
        module = dispatcher.py_func.__module__
        if module.startswith(f"{__package__}.baselines.") == baselines:
            found[module] = found.get(module, False) or bool(dispatcher._cache._cache_file._load_index())
    return all(found.values())


def warm_up(variants: Sequence[CBMParams] = VARIANTS,
            report: Callable[[CBMParams, float], None] | None = None) -> float:
    """Call ``match`` once per variant (``report(variant, seconds)`` after each), then make a sigma2
    edit (``sigma2_edit``); the seconds spent."""
    ego, cav, init = scene()
    started = time.perf_counter()
    for params in variants:
        before = time.perf_counter()
        match(ego, cav, init, params)
        if report is not None:
            report(params, time.perf_counter() - before)
    sigma2_edit()
    return time.perf_counter() - started


def sigma2_edit() -> None:
    """A first call and a sigma2 edit on the same input through ``Reuse``: the edit counts again
    and reads the members listed at the first sigma2 (``cbm.engine.listing``)."""
    reuse = Reuse()
    for params in (CBMParams(), CBMParams(sigma2=2.5)):
        build_sets(*checked_inputs(*scene(), params), reuse=reuse)


def compile_matching() -> None:
    """Compile steps 1-4 and the voting sets (context, the join, the grouping in one run and in
    several, the counts of a sigma2 edit) with first calls."""
    sigma2_edit()
    ego, cav, init, params = checked_inputs(*scene(), CBMParams())
    ready = prepare(ego, cav, init, params.heading)
    _, votes = counts_and_votes(ready, params.sigma1_rad, params.sigma2, params.sigma3)
    threshold, tuning.VOTES_APART_FROM = tuning.VOTES_APART_FROM, 0
    try:
        voted_by_member(votes, ready.signs.size)
    finally:
        tuning.VOTES_APART_FROM = threshold


def compile_selection() -> None:
    """Compile steps 5-7 (the visit, consensus, one-to-one rule, runner-up, the listing's writers
    closed up, the robust fit, the grouping of a large assignment, the evidence, the comparison of
    poses) with a first call on candidate sets whose sizes are upper bounds, without running the
    join that counts them."""
    ego, cav, init, params = checked_inputs(*scene(), CBMParams())
    ready = prepare(ego, cav, init, params.heading)
    n_ego, n_cav = ready.signs.shape
    bound = np.full(n_ego * n_cav, (n_ego - 1) * (n_cav - 1) + 1, np.int64)
    candidates = candidate_sets(ready, params.sigma1_rad, params.sigma2, bound)
    ego_xy, cav_xy = ego[:, :2], ready.cav_boxes[:, :2]
    sets = (candidates, PairSets.empty(n_ego * n_cav), params.consensus_rule, ego_xy, cav_xy, params.distance_limit)
    select(*sets)
    order = by_count_descending(bound)
    runner_up(RivalSearch(order, 0, 0, np.zeros(len(bound), bool), candidates, filtering(*sets)))
    filtered_sizes(order[:2], *sets)
    kept = new_listing(params.sigma2, bound)
    closed_up(kept, writers(kept, 2))
    robust_fit(cav_xy, ego_xy, params.welsch_floor)
    found = gated_assignment(ego, ready.cav_boxes, 3.0, 1.0)
    evidence(ego, ready.cav_boxes, found, 1.0, 1.0, found)
    same_pose(init, init)


def compile_baselines() -> None:
    """Compile the kernels of the baselines that have some (FreeAlign's common subgraph search) and
    what V2X-Reg++ calls of CBM's, with first calls."""
    from .baselines.freealign import match_freealign
    from .baselines.v2xregpp import match_v2xregpp

    ego, cav, init = scene()
    match_v2xregpp(ego, cav, init)
    match_freealign(ego, cav, init)


PARTS = {"matching": compile_matching, "selection": compile_selection, "baselines": compile_baselines}
CBM_PARTS = ("matching", "selection")
"""CBM's two halves, compiled side by side."""
BASELINE_PARTS = ("baselines",)
RUN_PART = "import sys, cbm.warmup; sys.exit(cbm.warmup.main())"
"""What a compiling process runs (``main`` with ``--part``)."""


class CompileFailed(RuntimeError):
    """A compiling process ended with an error."""


def compile_side_by_side(processes: list[subprocess.Popen] | None = None, timeout: float | None = None,
                         parts: Sequence[str] = CBM_PARTS) -> float:
    """The ``parts`` of the kernels (by default both halves of CBM's) at once, each in a process of
    its own (``main`` with ``--part NAME``; ``processes`` receives them, to be stopped by the caller
    if need be). Returns the seconds the slowest part spent compiling (or loading from the cache),
    without the processes' start-up; raises ``CompileFailed`` when one fails,
    ``subprocess.TimeoutExpired`` past ``timeout`` seconds."""
    root = Path(__file__).resolve().parents[1]
    started = [subprocess.Popen([sys.executable, "-c", RUN_PART, "--part", part], cwd=root, text=True,
                                stdout=subprocess.PIPE, stderr=subprocess.DEVNULL) for part in parts]
    if processes is not None:
        processes += started
    seconds = []
    for process in started:
        out, _ = process.communicate(timeout=timeout)
        if process.returncode != 0:
            raise CompileFailed(f"{' '.join(process.args[1:])} exited with {process.returncode}")
        seconds.append(float(out.split()[-2]))
    return max(seconds)


def _compile_part(name: str) -> None:
    """One half, timed: prints ``compiled S s``."""
    started = time.perf_counter()
    PARTS[name]()
    print(f"compiled {time.perf_counter() - started:.2f} s", flush=True)


def _print(params: CBMParams, seconds: float) -> None:
    changed = {k: v for k, v in vars(params).items() if v != getattr(CBMParams(), k)}
    print(f"variant {changed or 'defaults'}: {seconds:.2f} s", flush=True)


def main() -> int:
    parser = argparse.ArgumentParser(description="Compile CBM's numba kernels into numba's on-disk cache.")
    parser.add_argument("--part", choices=sorted(PARTS), help="compile one half only (used by the default run)")
    args = parser.parse_args()
    if args.part:
        _compile_part(args.part)
        return 0
    halves = compile_side_by_side()
    print(f"halves side by side: {halves:.2f} s", flush=True)
    baselines = compile_side_by_side(parts=BASELINE_PARTS)
    print(f"baselines: {baselines:.2f} s", flush=True)
    print(f"total {halves + baselines + warm_up(report=_print):.2f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
