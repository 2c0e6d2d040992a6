"""``loaders.open``: a dataset by name or path, with the loader picked from what is there.

The loaders are found, not listed: every module of the ``loaders`` package that says what it reads
(``EXPECTED``, beside its ``recognises(path)`` and ``load(path)``) is one (``registered``). A new
dataset is one module; nothing here changes.
"""
from __future__ import annotations

import importlib
import pkgutil
import re
from pathlib import Path
from types import ModuleType

from . import argoverse2, synthetic
from . import detections as detection_files
from .errors import LoaderError, existing_path, unreadable
from .scene import Sequence
from .structured import MAX_METRES

REPOSITORY_DATA = Path(__file__).resolve().parent / "data"
SYNTHETIC_NAME = re.compile(r"^synthetic(?::(?P<count>\d+))?(?::seed=(?P<seed>-?\d+))?$")


def repository_data(name: str) -> Path:
    """The folder of a scene shipped in the package's ``loaders/data/`` (e.g. ``"argoverse2"``)."""
    return REPOSITORY_DATA / name


def open(path_or_name: str | Path, detections: str | Path | None = None) -> Sequence:
    """Load a dataset (:func:`load`), with a detector's boxes from ``detections`` (a CoAlign / HEAL
    ``stage1_boxes.json``, see ``loaders.detections``) attached to its frames when given."""
    sequence = load(path_or_name)
    if detections is None:
        return sequence
    return detection_files.attach(sequence, existing_path(detections, "detections file"))


def load(path_or_name: str | Path) -> Sequence:
    """Load a dataset.

    ``"argoverse2"`` is the shipped default scene; ``"synthetic"``, ``"synthetic:<count>"`` and
    ``"synthetic:<count>:seed=<seed>"`` generate a scene (count 0 to ``synthetic.MAX_OBJECTS``,
    2000; seed a non-negative integer); anything else is a path to a regular dataset file or a
    folder, whose loader is picked from the files found there. Raises :class:`LoaderError` when the
    name or path cannot be loaded, naming the part of the name, or the file or folder, at fault.
    """
    if isinstance(path_or_name, str):
        match = SYNTHETIC_NAME.match(path_or_name.strip())
        if match:
            return _synthetic(path_or_name.strip(), match)
        if path_or_name.startswith("synthetic"):
            raise LoaderError(f"{path_or_name!r}: expected synthetic, synthetic:<count> or "
                              f"synthetic:<count>:seed=<seed>")
        if path_or_name == "argoverse2":
            return argoverse2.load(existing_path(repository_data("argoverse2"), "shipped scene"))
    path = existing_path(path_or_name)
    try:
        return within_bounds(_loader_for(path)(path), path)
    except OSError as error:
        raise unreadable(error, path) from None


def within_bounds(sequence: Sequence, path: Path) -> Sequence:
    """``sequence``, or a ``LoaderError`` naming the first position or size beyond
    ``structured.MAX_METRES`` (a number no scene has, which would overflow the trials later)."""
    where = sequence.beyond(MAX_METRES)
    if where is not None:
        raise LoaderError(f"{path}: {where}; expected positions and sizes within {MAX_METRES:.0e} m")
    return sequence


def _synthetic(name: str, match: re.Match) -> Sequence:
    """The synthetic scene a ``synthetic[:count][:seed=S]`` name asks for, its count and seed checked."""
    count = int(match["count"]) if match["count"] else 200
    seed = int(match["seed"] or 0)
    if count > synthetic.MAX_OBJECTS:
        raise LoaderError(f"{name}: count must be from 0 to {synthetic.MAX_OBJECTS}, got {count}")
    if seed < 0:
        raise LoaderError(f"{name}: seed must be a non-negative integer, got {seed}")
    return synthetic.generate(n_objects=count, seed=seed)


def _loader_for(path: Path):
    """The ``load`` function of the first registered loader that recognises ``path``."""
    found = registered()
    for module in found:
        if module.recognises(path):
            return module.load
    raise LoaderError(f"{path}: nothing recognisable; expected {expected(found)}")


def registered() -> list[ModuleType]:
    """The loaders, in the order they are tried: the modules of this package that define
    ``EXPECTED``, by name, those that recognise broadly (``BROAD``: any table file, any YAML file)
    after the others."""
    package = importlib.import_module(__package__)
    modules = [importlib.import_module(f"{__package__}.{info.name}") for info in pkgutil.iter_modules(package.__path__)]
    loaders = [module for module in modules if hasattr(module, "EXPECTED")]
    return sorted(loaders, key=lambda module: (getattr(module, "BROAD", False), module.__name__))


def expected(loaders: list[ModuleType]) -> str:
    """What ``loaders`` read, as one list: "a, b, or c"."""
    names = [module.EXPECTED for module in loaders]
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])}, or {names[-1]}"

