"""Where a tab starts: on the settings' frame when CBM can run on it, else on the first frame after
it that it can (a recording whose first frames hold one or two agents, as INTERACTION's and SinD's
often do), with a note that says so; and when no frame can, a note that says that and why.

CBM can run on a frame when the frame makes a trial (an ego and a CAV) in which both agents see at
least ``FEWEST_SHARED`` of the same objects: with fewer, no answer can be right, and CBM abstains.
"""
from __future__ import annotations

import dataclasses

from .explorer import Explorer
from .settings import Settings

FEWEST_SHARED = 3
"""Objects both agents must see for CBM to stand by a pose: with two, any pose fits them exactly
(``cbm.MatchResult.abstained``: "fewer than 3 objects could be paired")."""
SCANNED = 2000
"""Frames after the start looked at for one CBM can run on (a trial is built for each)."""


def shared_objects(explorer: Explorer, settings: Settings, index: int) -> int | None:
    """How many objects both the ego and the CAV see on frame ``index`` under ``settings`` (the
    trial's true pairs); None when the frame has no ego and CAV."""
    try:
        inputs = explorer.trial_inputs(settings, index)
    except ValueError:
        return None
    return len(inputs.build(settings.scenario, settings.scenario.seed).gt_pairs)


def runs_on(explorer: Explorer, settings: Settings, index: int) -> bool:
    """Whether CBM can run on frame ``index`` under ``settings`` (see the module)."""
    shared = shared_objects(explorer, settings, index)
    return shared is not None and shared >= FEWEST_SHARED


def first_usable(explorer: Explorer, settings: Settings, frames: range | list[int]) -> int | None:
    """The first of ``frames`` CBM can run on under ``settings``; None when there is none."""
    return next((index for index in frames if runs_on(explorer, settings, index)), None)


def start_of(explorer: Explorer, settings: Settings) -> tuple[Settings, str | None]:
    """The settings a tab starts from and, when the frame moved or no frame can run, the note that
    says so: the settings as given when their frame can run; else on the first frame after it that
    can; else on the first with an ego and a CAV (the page then says what is missing)."""
    frame, protocol = settings.frame, settings.scenario.protocol
    if frame >= len(explorer) or runs_on(explorer, settings, frame):
        return settings, None
    frames = range(frame + 1, min(len(explorer), frame + 1 + SCANNED))
    found = first_usable(explorer, settings, frames)
    if found is not None:
        note = (f"frame {frame} has fewer than {FEWEST_SHARED} objects seen by both an ego and a CAV under the "
                f"{protocol} protocol, too few for CBM to stand by a pose; frame {found}, the first with enough, "
                f"is shown")
        return dataclasses.replace(settings, frame=found), note
    shared = {index: shared_objects(explorer, settings, index) for index in range(frame, frames.stop)}
    paired = [index for index, count in shared.items() if count is not None]
    most = max((shared[index] for index in paired), default=0)
    looked = f"of the {frames.stop - frame} frames looked at" if frames.stop < len(explorer) else "of this dataset"
    if not paired:
        return settings, f"no frame {looked} has an ego and a CAV under the {protocol} protocol"
    note = (f"no frame {looked} has {FEWEST_SHARED} objects seen by both an ego and a CAV under the {protocol} "
            f"protocol (at most {most}): CBM abstains, whatever it finds; frame {paired[0]}, the first with an ego "
            f"and a CAV, is shown")
    return dataclasses.replace(settings, frame=paired[0]), note
