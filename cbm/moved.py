"""Modules that moved out of ``cbm`` (the method) into ``evaluation`` (what measures it) in 0.2.

Their old names still import for one release, with a ``DeprecationWarning`` naming the new place:

    from cbm.metrics import evaluate        # works, warns: cbm.metrics moved to evaluation.metrics
    from evaluation.metrics import evaluate # the name to use

The alias is the very module of its new place (not a copy). ``cbm`` itself imports nothing of the
project: the new module is only imported when an old name is asked for.
"""
from __future__ import annotations

import importlib
import importlib.abc
import sys
import warnings
from importlib.machinery import ModuleSpec
from types import ModuleType

MOVED = {f"cbm.{name}": f"evaluation.{name}"
         for name in ("ap", "detected", "diagnosis", "executors", "fusion", "metrics", "scenario", "search", "sweep")}
"""Old module name -> new module name."""


class _Aliases(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds the old names of ``MOVED`` and loads each as its new module."""

    def __init__(self) -> None:
        self._specs: dict[str, ModuleSpec] = {}
        """Each new module's own spec by old name (the import system overwrites it with the alias's)."""

    def find_spec(self, fullname: str, path: object = None, target: object = None) -> ModuleSpec | None:
        return ModuleSpec(fullname, self) if fullname in MOVED else None

    def create_module(self, spec: ModuleSpec) -> ModuleType:
        new = MOVED[spec.name]
        warnings.warn(f"{spec.name} moved to {new}; the old name goes in the next release",
                      DeprecationWarning, stacklevel=2)  # the frames of the import system are skipped
        module = importlib.import_module(new)
        self._specs[spec.name] = module.__spec__
        return module

    def exec_module(self, module: ModuleType) -> None:
        module.__spec__ = self._specs[module.__spec__.name]


def install() -> None:
    """Let the old names import (once per interpreter)."""
    if not any(isinstance(finder, _Aliases) for finder in sys.meta_path):
        sys.meta_path.append(_Aliases())
