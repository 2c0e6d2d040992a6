"""Issue 50, item 10: the measuring layer uses no private internals of Python or of a library
(were: ``multiprocessing.util._run_finalizers``, ``pool._processes``, ``pool._executor_manager_thread``),
which change between Python versions without notice."""
from __future__ import annotations

import ast
from pathlib import Path

EVALUATION = Path(__file__).resolve().parents[2] / "evaluation"
DOCUMENTED = {"os._exit"}
"""Underscored names that are public, documented API."""


def private_uses(path: Path) -> list[str]:
    """``owner._name`` of every attribute read on anything but ``self`` or ``cls``, dunders aside."""
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Attribute) and node.attr.startswith("_") and not node.attr.startswith("__"):
            owner = ast.unparse(node.value)
            if owner not in ("self", "cls") and f"{owner}.{node.attr}" not in DOCUMENTED:
                found.append(f"{path.name}:{node.lineno}: {owner}.{node.attr}")
    return found


def test_no_private_attribute_of_another_object_is_used() -> None:
    assert [use for path in sorted(EVALUATION.glob("*.py")) for use in private_uses(path)] == []
