"""Where a tab starts: on the settings' frame when CBM can run on it, else on the first frame after
it that can (a recording whose first frames hold one agent, as INTERACTION's and SinD's often do),
with a note that says so."""
from __future__ import annotations

import dataclasses

from .explorer import Explorer
from .settings import Settings


def runs_on(explorer: Explorer, settings: Settings, index: int) -> bool:
    """Whether frame ``index`` makes a trial under ``settings`` (an ego and a CAV) with objects to match."""
    try:
        explorer.trial_inputs(settings, index)
    except ValueError:
        return False
    return len(explorer.sequence[index].track_ids) >= 2


def first_usable(explorer: Explorer, settings: Settings, frames: range | list[int]) -> int | None:
    """The first of ``frames`` CBM can run on under ``settings``; None when there is none."""
    return next((index for index in frames if runs_on(explorer, settings, index)), None)


def start_of(explorer: Explorer, settings: Settings) -> tuple[Settings, str | None]:
    """The settings a tab starts from and, when the frame moved, the note that says why; the settings
    as given when their frame can run, or when no frame after it can (the page then says what is missing)."""
    frame = settings.frame
    if frame >= len(explorer) or runs_on(explorer, settings, frame):
        return settings, None
    found = first_usable(explorer, settings, range(frame + 1, len(explorer)))
    if found is None:
        return settings, None
    note = (f"CBM cannot run on frame {frame} (no ego and CAV with objects to match under the "
            f"{settings.scenario.protocol} protocol); frame {found} is the first it can run on")
    return dataclasses.replace(settings, frame=found), note
