"""Parameter search from the app: ``evaluation.search`` over the tab's sequence and scenario, with the
tab's current thresholds scored the same way for comparison.

Runs on one core (the other stays with the tabs) so that a cancel, checked as every frame's rows
arrive, stops it at once.
"""
from __future__ import annotations

from dataclasses import dataclass

from cbm.methods import METHODS
from evaluation.search import SEARCHABLE, Candidate, grid_size, search

from .background import Task
from .explorer import Explorer
from .sequence import frame_inputs
from .settings import Settings

OBJECTIVE_LABELS = {"success": "success rate (RTE < 1 m, RRE < 1°)", "f1": "F1", "precision": "precision",
                    "recall": "recall"}


@dataclass(frozen=True)
class SearchResult:
    """Every grid point, best first, and the tab's current thresholds, scored on the same frames."""

    settings: Settings
    objective: str
    frames: tuple[int, ...]
    candidates: tuple[Candidate, ...]
    current: Candidate

    def option(self, rank: int) -> str:
        """The label of the ``rank``-th best setting (0-based) in the apply list."""
        c = self.candidates[rank]
        return f"#{rank + 1} " + " ".join(f"{name} {value:g}" for name, value in c.params.items()) + f" · {c.score:.3f}"


def run_search(explorer: Explorer, settings: Settings, objective: str = "success", stride: int = 1,
               task: Task | None = None) -> SearchResult:
    """Search ``DEFAULT_SPACE`` on every ``stride``-th frame under the tab's scenario, seed, CAV
    rule and fixed CBM parameters; then score the tab's current thresholds the same way."""
    frames, _ = frame_inputs(explorer, settings, range(0, len(explorer), max(1, stride)))
    if not frames:
        raise ValueError("no frame of this sequence has an ego and a CAV")
    cbm = settings.cbm
    base = {name: getattr(cbm, name) for name in METHODS["cbm"].tunable}
    total = (grid_size() + 1) * len(frames)
    done = [0]

    def progress(n: int) -> None:
        done[0] += n
        if task is not None:
            task.check()
            task.report(done[0] / total)

    common = {"objective": objective, "base": base, "seed": settings.scenario.seed, "progress": progress}
    candidates = search(frames, settings.scenario, **common)
    current = search(frames, settings.scenario, space={n: [getattr(cbm, n)] for n in SEARCHABLE}, **common)[0]
    return SearchResult(settings, objective, tuple(f.index for f in frames), tuple(candidates), current)
