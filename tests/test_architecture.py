"""The four layers and what each may import (docs/architecture.md), read from the code itself.

    app -> evaluation -> loaders -> cbm        (presets: data, read by app and evaluation)

Every import statement of the project's packages is read with ``ast`` (those inside functions too),
relative ones resolved, and held against the rule: no arrow runs upwards, loaders take at most
``cbm.se2`` from the method, and no two modules import each other, directly or round a circle.
"""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
LAYERS = ("cbm", "loaders", "evaluation", "app")
"""From the bottom up: a package may import the ones below it, never one above."""
PACKAGES = (*LAYERS, "presets")
MAX_LINES = 400


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(REPO).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path) -> set[tuple[str, str]]:
    """The project names ``path`` imports as (module, name): ``import a.b`` gives ("a.b", ""),
    ``from a import b`` gives ("a", "b"), relative ones resolved."""
    name = _module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[tuple[str, str]] = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found.update((alias.name, "") for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")
                anchor = anchor[:len(anchor) - (node.level - 1)]
                base = ".".join([*anchor, base] if base else anchor)
            found.update((base, alias.name) for alias in node.names)
    return {(module, what) for module, what in found if module.split(".")[0] in PACKAGES}


def _sources() -> dict[str, Path]:
    return {_module_name(path): path for package in PACKAGES for path in sorted((REPO / package).rglob("*.py"))}


SOURCES = _sources()
MODULES = set(SOURCES)


def _graph() -> dict[str, set[str]]:
    """Module -> the project modules it imports (``from pkg import name`` counts as ``pkg.name``
    where that is a module, else as ``pkg``)."""
    graph = {}
    for name, path in SOURCES.items():
        targets = {f"{module}.{what}" if f"{module}.{what}" in MODULES else module for module, what in _imports(path)}
        graph[name] = {target for target in targets if target in MODULES and target != name}
    return graph


GRAPH = _graph()


def _layer(module: str) -> int:
    top = module.split(".")[0]
    return LAYERS.index(top) if top in LAYERS else -1


def test_the_rule_sees_every_package_and_their_imports() -> None:
    assert {name.split(".")[0] for name in SOURCES} == set(PACKAGES)
    assert "cbm.pipeline" in GRAPH["cbm"] and "evaluation.scenario" in GRAPH["evaluation.trials"]
    assert any(target.startswith("loaders") for target in GRAPH["evaluation.trials"])


@pytest.mark.parametrize("module", sorted(GRAPH))
def test_no_import_runs_upwards(module: str) -> None:
    upward = sorted(t for t in GRAPH[module] if _layer(t) > _layer(module) and t.split(".")[0] in LAYERS)
    assert not upward, f"{module} imports {upward}: the layers are {' -> '.join(reversed(LAYERS))}"


def test_the_presets_are_read_by_the_app_and_the_evaluation_and_import_nothing() -> None:
    readers = sorted(m for m, targets in GRAPH.items() if any(t.split(".")[0] == "presets" for t in targets))
    assert readers and all(m.startswith(("app.", "evaluation.")) for m in readers)
    assert not GRAPH["presets"]


def test_loaders_take_at_most_se2_from_the_method() -> None:
    taken = {t for m, targets in GRAPH.items() if m.startswith("loaders") for t in targets if t.startswith("cbm")}
    assert taken <= {"cbm.se2"}, sorted(taken)


def test_the_method_imports_nothing_of_the_project_but_itself() -> None:
    imported = {t.split(".")[0] for m, targets in GRAPH.items() if m.startswith("cbm") for t in targets}
    assert imported <= {"cbm"}


PUBLIC_CBM = ("cbm", "cbm.methods", "cbm.reference")
"""What app/, evaluation/ and loaders/ may import from the method: ``cbm``'s face (its ``__all__``),
the method registry and the reference."""


def test_outside_cbm_only_its_public_face_is_imported() -> None:
    import cbm

    inside = [(m, module, what) for m, path in SOURCES.items() if not m.startswith("cbm")
              for module, what in _imports(path) if module.split(".")[0] == "cbm"]
    private = sorted({f"{module}:{what}" for _, module, what in inside
                      if module not in PUBLIC_CBM or (module == "cbm" and what not in cbm.__all__)})
    assert not private, f"names of cbm used from outside it that cbm/__init__.py does not export: {private}"


def _floor(module: str, graph: dict[str, set[str]], seen: dict[str, int]) -> int:
    """1 for a module that imports nothing of its package, else one above the highest it imports."""
    if module not in seen:
        seen[module] = 1 + max((_floor(t, graph, seen) for t in graph[module]), default=0)
    return seen[module]


def test_cbm_stands_on_at_most_seven_floors() -> None:
    """Rooms as the picture of the house counts them: ``cbm/engine/`` and ``cbm/baselines/`` are one
    room each (their inside arrows do not count), every other module of ``cbm`` one."""
    def room(module: str) -> str:
        return ".".join(module.split(".")[:2]) if module.startswith(("cbm.engine", "cbm.baselines")) else module

    graph: dict[str, set[str]] = {}
    for module, targets in GRAPH.items():
        if module.startswith("cbm.") or module == "cbm":
            graph.setdefault(room(module), set()).update(room(t) for t in targets if room(t) != room(module))
    seen: dict[str, int] = {}
    floors = {module: _floor(module, graph, seen) for module in graph if module != "cbm"}
    assert max(floors.values()) <= 7, sorted(floors.items(), key=lambda item: -item[1])


def test_no_circle_of_imports() -> None:
    circles = [sorted(group) for group in _strongly_connected(GRAPH) if len(group) > 1]
    assert not circles, f"modules that import each other: {circles}"


def test_no_source_file_is_longer_than_the_limit() -> None:
    long = {name: n for name, path in SOURCES.items() if (n := len(path.read_text().splitlines())) > MAX_LINES}
    assert not long, f"files over {MAX_LINES} lines: {long}"


def _strongly_connected(graph: dict[str, set[str]]) -> list[set[str]]:
    """Tarjan's strongly connected components (iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    groups: list[set[str]] = []
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                group = set()
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    group.add(member)
                    if member == node:
                        break
                groups.append(group)
    return groups
