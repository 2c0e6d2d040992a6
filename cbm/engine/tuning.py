"""How many threads the engine uses, and from what size each kernel's work is shared out.

The thread count follows the CPUs this process may run on (``os.sched_getaffinity``: a container's
or ``taskset``'s limit, not the machine's), or ``CBM_THREADS``. Each threshold below is the size
from which handing a kernel's work to the threads (``cbm.engine.threads.shared_out``) saved more
than it cost, measured on a 2-core machine with ``bench/bench_steps.py`` and ``bench/bench_edit.py``
(docs/benchmarks.md); on more cores the hand-over costs the same and saves more, so the thresholds
are lower bounds there. Every threshold only decides the speed: the engine's results are the same
with every one at 0 (every hand-over taken) or infinite (none), at any thread count
(``tests/cbm/test_engine_threads.py``). The engine reads them at call time, so a test can set them.
"""
from __future__ import annotations

import os


def available_threads() -> int:
    """``CBM_THREADS`` when set (a positive integer), else the CPUs this process may use."""
    asked = os.environ.get("CBM_THREADS", "").strip()
    if asked:
        if not asked.isdigit() or int(asked) < 1:
            raise ValueError(f"CBM_THREADS must be a positive integer, got {asked!r}")
        return int(asked)
    try:
        return max(len(os.sched_getaffinity(0)), 1)
    except AttributeError:  # no sched_getaffinity (macOS, Windows)
        return os.cpu_count() or 1


THREADS = available_threads()
"""Threads the engine's kernels run on at once, the calling thread included."""

GROUPS_APART_FROM = 5_000
"""Context vectors per agent from which the join's heading groups are shared out between the
threads, each group whole (its grid and its join): local matching 0.8-0.95x the time of splitting
every group, from 100 to 1000 objects per agent."""
GROUP_PARTS_FROM = 20_000
"""Context vectors per agent from which one heading group is joined in parts of its ego objects:
on the threads when it is the only group (``heading="fold"``), else one part after another, so
that a part's vote list, grown and copied to fit, is a fraction of the group's (63 MB less at
once at 1000 objects per agent, dense)."""
BLOCKS_APART_FROM = 20_000
"""Context vectors per agent from which both agents' sorted blocks are sorted at once."""
DISTANCES_APART_FROM = 5_000
"""Context vectors per agent from which a first sigma2 edit keeps the quadruples' distances
(``cbm.engine.distances``) on the threads (it writes every quadruple it accepts: synthetic:300's
frame 12.5 -> 7.8 ms)."""
COUNT_APART_FROM = 200_000
"""Quadruples kept from which a sigma2 edit counts them on the threads, each part into counters
of its own (synthetic:1000's frame, 2.4 M quadruples: 3.3-3.9 -> 2.1 ms)."""
VOTES_APART_FROM = 200_000
"""Vote rows from which the voting sets are grouped in parts on the threads (dense 300: 12.8 ->
9.2 ms; dense 1000: 674 -> 514 ms)."""
VISIT_APART_FROM = 5_000
"""Ego x CAV pairs from which eq. 13's visit may be shared out (below, never worth a hand-over)."""
VISIT_AHEAD_FROM = 10_000
"""Candidate pairs ahead of eq. 13's visit (the anchors it may still reach) from which it is
shared out: dense 100's consensus and selection 1.17 -> 0.98 ms with this bound against none."""
RIVAL_PAIRS_FROM = 10_000
"""Candidate pairs in a chunk of the runner-up search from which the chunk is shared out:
street 300's selection 16.5 -> 12-13 ms, street 1000's 108 -> 65-91 ms."""

RIVAL_BESIDE_FROM = 5_000
RIVAL_BESIDE_BELOW = 40_000
"""Ego x CAV pairs from and below which the runner-up search runs beside the verification of the
winner, on a thread of its own (without a listing): street 100's match 7.7 -> 6.3 ms, dense 100's
6.6 -> 5.9 ms. Below, the hand-over costs more than it saves; from the upper end the search is
better shared out itself (``RIVAL_PAIRS_FROM``)."""

THRESHOLDS = ("GROUPS_APART_FROM", "GROUP_PARTS_FROM", "BLOCKS_APART_FROM", "DISTANCES_APART_FROM",
              "COUNT_APART_FROM", "VOTES_APART_FROM", "VISIT_APART_FROM", "VISIT_AHEAD_FROM", "RIVAL_PAIRS_FROM",
              "RIVAL_BESIDE_FROM", "RIVAL_BESIDE_BELOW")
"""Every hand-over threshold above, by name."""

VISIT_FIRST = 32
"""Anchors eq. 13's visit takes on the calling thread before it shares the rest out: the first
anchors have the largest sets, and most visits end within them (synthetic:1000 sigma2 edit 30.9 ->
24.3 ms against 128)."""
RIVAL_FIRST = 64
"""Anchors the runner-up search visits on the calling thread before it shares any out."""
RIVAL_CHUNK = 512
"""Anchors the runner-up search shares out at a time."""
