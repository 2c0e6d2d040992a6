"""What a run's inputs may cost, told before it starts: ``--workers`` bounded by the machine's CPUs,
``--agents`` beyond what the frames have, and the pose graph's cost (``evaluate.py`` prints these
as warnings); a ``--grid`` of too many points is refused before it is expanded."""
from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from typing import Any

from .run import Plan

GRAPH_WARNING_CAVS = 8
"""CAVs per frame from which ``cbm-graph``'s cost (CBM on every CAV for each CAV's trial) is warned about."""


def bounded_workers(workers: int, ray: str | None) -> tuple[int, str | None]:
    """``--workers`` at most this machine's CPUs (a process pool spawns one worker per pending task up
    to it, each over 100 MB), and the warning saying so; a Ray cluster sizes itself."""
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    if ray not in (None, "local") or workers <= cpus:
        return workers, None
    return cpus, (f"--workers {workers}: this machine has {cpus} CPU(s) for this process; using {cpus} "
                  "(more workers would share them and each take its own memory)")


def cost_warnings(planned: Plan, agents: int) -> list[str]:
    """What the user should know of ``--agents`` before the run: more agents asked for than the
    frames have, and the pose graph's cost, quadratic in the frame's CAVs."""
    most = planned.most_cavs
    found = []
    if agents - 1 > most:
        found.append(f"--agents {agents}: the chosen frames have at most {most + 1} agents (the ego and {most} "
                     f"CAV(s)), so a frame gives at most {most} trial(s) per method")
    if "cbm-graph" in planned.sweep.methods and most >= GRAPH_WARNING_CAVS:
        found.append(f"--agents {agents}: cbm-graph matches every CAV of the frame for each CAV's trial: up to "
                     f"{most * most} CBM runs per frame and scenario point ({most} for cbm); this may take hours")
    return found


MAX_GRID_POINTS = 100_000
"""Points of ``--grid`` (the product of its value counts) one run may take: each is a row per frame
and method, and the sweep lists them all before it starts."""


def grid_too_large(grid: Mapping[str, Sequence[Any]]) -> str | None:
    """What is wrong with a grid whose points exceed :data:`MAX_GRID_POINTS` (counted, not listed), or None."""
    points = math.prod(len(values) for values in grid.values())
    if points <= MAX_GRID_POINTS:
        return None
    sizes = " x ".join(f"{len(values)} {name}" for name, values in grid.items())
    return f"--grid: {points:,} points ({sizes}); at most {MAX_GRID_POINTS:,} in one run"
