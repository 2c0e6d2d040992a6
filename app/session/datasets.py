"""The datasets a server offers its tabs: the shipped scene, the one it started on, and every dataset
found under the folders named at start (``--data``), each opened on the first ask and kept, one
``Explorer`` per dataset that the tabs showing it share.

Nothing outside those folders is listed or read. A tab picks a dataset by its name among those
listed, never by a path; the search follows no link that leads out of the folders (nor into a
folder it has seen), asks the loaders about no folder with such a link in its first two levels
(where they look), and a dataset is opened only after every link in it was checked again to stay
inside (a link made after the search changes nothing). A folder is a dataset when a loader
recognises it (``loaders.dispatch.registered``, in the order ``loaders.open`` tries them); the search
does not look inside a dataset, and lists the table files (CSV, Parquet) of a folder no loader
recognises, which the generic table loader reads. A folder only a loosely recognising loader takes
(``BROAD``: OPV2V's numbered folders of YAML files) holding a folder a strict one takes is a folder
of datasets, not one.
"""
from __future__ import annotations

import dataclasses
import os
import threading
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

import loaders
from loaders.dispatch import registered

from .explorer import Explorer
from .offers import offers_of
from .settings import AUTO_CAV, Settings

SHIPPED = "argoverse2"
"""The scene shipped with the package (``loaders.open("argoverse2")``)."""
DEPTH = 4
"""Folders below a ``--data`` folder that the search goes into."""
MOST = 200
"""Datasets listed at most."""
CHECKED = 200_000
"""Entries of a dataset checked for links that lead out, at most (past it the dataset is refused)."""
TABLES = (".csv", ".parquet", ".feather", ".arrow")


class DataError(ValueError):
    """A dataset or a ``--data`` folder that cannot be offered, in one line naming it."""


@dataclass(frozen=True)
class Dataset:
    """One dataset offered: its name in the picker, what ``loaders.open`` is given, its loader."""

    name: str
    source: str | Path
    kind: str


def data_roots(folders: Iterable[str | Path]) -> list[Path]:
    """The ``--data`` folders, resolved (links followed once, here); ``DataError`` naming one that is
    not a folder."""
    roots = []
    for folder in folders:
        path = Path(folder).expanduser()
        if not path.is_dir():
            raise DataError(f"--data {folder}: not a folder")
        roots.append(path.resolve())
    return roots


def inside(path: Path, roots: Sequence[Path]) -> bool:
    """Whether ``path``, its links followed, lies in one of ``roots``."""
    resolved = path.resolve()
    return any(resolved == root or resolved.is_relative_to(root) for root in roots)


def found(roots: Sequence[Path], depth: int = DEPTH, most: int = MOST) -> list[Dataset]:
    """Every dataset under ``roots`` (see the module), at most ``most`` (the shallowest first), by name."""
    loaders_tried = registered()
    datasets: list[Dataset] = []
    seen: set[Path] = set()
    for root in roots:
        waiting = [(root, 0)]
        while waiting and len(datasets) < most:
            folder, level = waiting.pop(0)
            if folder.resolve() in seen or not inside(folder, roots):
                continue
            seen.add(folder.resolve())
            entries = _entries(folder)
            kind = None if escape(folder, roots, levels=2) else _recognised(folder, loaders_tried, entries)
            if kind is not None:
                datasets.append(Dataset(_name(root, folder), folder, kind))
                continue
            datasets += [Dataset(_name(root, path), path, "table") for path in entries
                         if path.suffix.lower() in TABLES and path.is_file() and inside(path, roots)]
            if level < depth:
                waiting += [(path, level + 1) for path in entries if path.is_dir()]
    return sorted(datasets[:most], key=lambda dataset: dataset.name)


def escape(path: Path, roots: Sequence[Path], most: int = CHECKED, levels: int | None = None) -> str | None:
    """The first entry of ``path`` (itself, or a file or folder under it, ``levels`` deep at most:
    None, all) whose links lead out of ``roots``, in words; None when none does."""
    if not inside(path, roots):
        return f"{path.name} lies outside the data folders"
    if not path.is_dir():
        return None
    count = 0
    for folder, folders, files in os.walk(path):
        if levels is not None and len(Path(folder).relative_to(path).parts) >= levels:
            folders.clear()
            continue
        for name in (*folders, *files):
            count += 1
            entry = Path(folder) / name
            if entry.is_symlink() and not inside(entry, roots):
                return f"{entry.relative_to(path)} links outside the data folders"
            if count > most:
                return f"more than {most} files to check"
    return None


class Catalogue:
    """The datasets offered by name, the first the one the server started on, and each one's
    ``Explorer`` once opened."""

    def __init__(self, first: Dataset, explorer: Explorer, roots: Sequence[Path] = (), shipped: bool = True) -> None:
        self.roots = list(roots)
        offered = [first, *([] if first.source == SHIPPED or not shipped else [start_dataset(SHIPPED)]),
                   *(dataset for dataset in found(self.roots) if not _same(dataset.source, first.source))]
        self.datasets = {dataset.name: dataset for dataset in _unique(offered)}
        self.first = first.name
        self._explorers = {first.name: explorer}
        self._lock = threading.Lock()
        self._opening: dict[str, threading.Lock] = {}

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(self.datasets)

    @property
    def explorers(self) -> list[Explorer]:
        """The datasets opened so far."""
        with self._lock:
            return list(self._explorers.values())

    def explorer(self, name: str) -> Explorer:
        """The ``Explorer`` of the dataset ``name`` (loaded on the first ask, once however many tabs
        ask at once); ``DataError`` for a name not offered or a dataset with a link out of the data
        folders, ``loaders.LoaderError`` for one that does not load."""
        dataset = self.datasets.get(name)
        if dataset is None:
            raise DataError(f"{name!r} is not a dataset offered here")
        with self._lock:
            opening = self._opening.setdefault(name, threading.Lock())
        with opening:
            with self._lock:
                if name in self._explorers:
                    return self._explorers[name]
            if isinstance(dataset.source, Path):
                why = escape(dataset.source, self.roots)
                if why is not None:
                    raise DataError(f"{name}: not opened, {why}")
            sequence = loaders.open(dataset.source)
            if len(sequence) == 0:
                raise DataError(f"{name}: the dataset has no frames")
            with self._lock:
                self._explorers[name] = Explorer(sequence)
                return self._explorers[name]


def settings_on(settings: Settings, explorer: Explorer, fallback: Settings) -> Settings:
    """A tab's ``settings`` carried to another dataset: from its first frame, the CAV chosen anew;
    ``fallback``'s (the server's start settings) when the dataset cannot offer them."""
    moved = dataclasses.replace(settings, frame=0, cav=AUTO_CAV)
    if offers_of(explorer.sequence).refusal(moved) is None:
        return moved
    return dataclasses.replace(fallback, frame=0, cav=AUTO_CAV)


def start_dataset(name: str) -> Dataset:
    """The dataset the server starts on, as ``--dataset`` names it."""
    if name == SHIPPED:
        return Dataset(f"{SHIPPED} (shipped)", SHIPPED, "argoverse2")
    path = Path(name)
    return Dataset(path.name or name, path.resolve() if path.exists() else name, "start")


def _same(a: str | Path, b: str | Path) -> bool:
    """Whether two sources name the same dataset (paths compared with their links followed)."""
    return Path(a).resolve() == Path(b).resolve() if isinstance(a, Path) and isinstance(b, Path) else a == b


def _recognised(folder: Path, tried: list, entries: list[Path]) -> str | None:
    """The name of the first loader that recognises ``folder`` (of ``entries``), None when none does
    or only a loose one does while a strict one recognises one of its folders."""
    module = _first(folder, tried)
    if module is None:
        return None
    if getattr(module, "BROAD", False):
        strict = [other for other in tried if not getattr(other, "BROAD", False)]
        if any(_first(entry, strict) is not None for entry in entries if entry.is_dir()):
            return None
    return module.__name__.rsplit(".", 1)[-1]


def _first(path: Path, tried: list):
    """The first of the loaders ``tried`` that recognises ``path``; None when none does."""
    for module in tried:
        try:
            if module.recognises(path):
                return module
        except OSError:
            return None
    return None


def _entries(folder: Path) -> list[Path]:
    """The folder's entries by name; none when it cannot be read."""
    try:
        return sorted(folder.iterdir())
    except OSError:
        return []


def _name(root: Path, path: Path) -> str:
    """A dataset's name in the picker: its path from its ``--data`` folder's parent."""
    return str(Path(root.name) / path.relative_to(root)) if path != root else root.name


def _unique(datasets: list[Dataset]) -> list[Dataset]:
    """``datasets``, a name given twice made unique by a number ("name (2)")."""
    named: dict[str, int] = {}
    unique = []
    for dataset in datasets:
        named[dataset.name] = named.get(dataset.name, 0) + 1
        count = named[dataset.name]
        unique.append(dataset if count == 1 else Dataset(f"{dataset.name} ({count})", dataset.source, dataset.kind))
    return unique
