"""Which settings two results were computed under differ, in the words and units the controls show:
what a result computed under other settings says of itself (a stale sequence run, a pinned
baseline) and what *jump there* will set before it sets it."""
from __future__ import annotations

import dataclasses
from typing import Any, NamedTuple

from cbm.methods import METHODS

from ..session.settings import Settings
from .words import SCENARIO_WORDS, TRACKING, label_of


class Difference(NamedTuple):
    """One setting that differs: its label, its value in the first settings and in the second."""

    label: str
    first: str
    second: str


def shown(value: Any) -> str:
    """A setting's value as the page prints it."""
    if isinstance(value, bool):
        return "on" if value else "off"
    return f"{value:g}" if isinstance(value, float) else str(value)


def differences(first: Settings, second: Settings) -> list[Difference]:
    """The settings a result depends on (method, its parameters and, for a method over time, its
    tracking, scenario, CAV) that differ between ``first`` and ``second``; the frame and the view
    options are not among them."""
    found = []
    if first.method != second.method:
        found.append(Difference("method", METHODS[first.method].label, METHODS[second.method].label))
    for key in dict.fromkeys(METHODS[m].params_key for m in (first.method, second.method)):
        found += _differing(key, first.method_params[key], second.method_params[key])
    if METHODS[first.method].over_time or METHODS[second.method].over_time:
        found += _differing(TRACKING, first.tracking, second.tracking)
    found += [Difference(label, shown(getattr(first.scenario, name)), shown(getattr(second.scenario, name)))
              for name, label in SCENARIO_WORDS.items()
              if getattr(first.scenario, name) != getattr(second.scenario, name)]
    if first.cav != second.cav:
        found.append(Difference("CAV", first.cav, second.cav))
    if first.cavs != second.cavs:
        found.append(Difference("CAVs", str(first.cavs), str(second.cavs)))
    return found


def _differing(key: str, a: Any, b: Any) -> list[Difference]:
    """The fields of the parameter set ``key`` whose values differ between ``a`` and ``b``."""
    return [Difference(label_of(key, f.name), shown(getattr(a, f.name)), shown(getattr(b, f.name)))
            for f in dataclasses.fields(a) if getattr(a, f.name) != getattr(b, f.name)]


def now_words(found: list[Difference]) -> str:
    """``found`` as "σp (m) 0.2 (now 0.9), seed 0 (now 3)": the first settings' values, then the second's."""
    return ", ".join(f"{d.label} {d.first} (now {d.second})" for d in found)


def change_lines(found: list[Difference]) -> str:
    """``found`` as a Markdown list of changes from the second settings' values to the first's."""
    return "\n".join(f"- {d.label}: {d.second} → {d.first}" for d in found)
