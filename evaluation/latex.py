"""The summary as a LaTeX table for papers (``summary.tex``, booktabs): one row per method,
precision, recall, success rate, median RTE and median RRE, the best of each column in bold."""
from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from .aggregates import SUCCESS_RRE_DEG, SUCCESS_RTE_M

COLUMNS = (
    ("Precision (\\%)", "precision", 100.0, 1, max),
    ("Recall (\\%)", "recall", 100.0, 1, max),
    ("Success (\\%)", "success_rate", 100.0, 1, max),
    ("Median RTE (m)", "median_rte", 1.0, 2, min),
    ("Median RRE (deg)", "median_rre", 1.0, 2, min),
)
"""Header, ``metrics.json`` key, scale, decimals and what is best."""
REFERENCES = ("none", "oracle")
"""Reference methods: shown, but not in the running for best (oracle has the true pairs)."""
SPECIAL = {"\\": "\\textbackslash{}", "&": "\\&", "%": "\\%", "$": "\\$", "#": "\\#", "_": "\\_",
           "{": "\\{", "}": "\\}", "~": "\\textasciitilde{}", "^": "\\textasciicircum{}"}


def escape(text: str) -> str:
    """``text`` with LaTeX's special characters escaped."""
    return "".join(SPECIAL.get(c, c) for c in text)


def shown(value: Any, scale: float, decimals: int) -> str:
    """The cell text of a value: scaled and rounded, ``--`` when nothing was measured."""
    if value is None or math.isnan(value):
        return "--"
    return f"{value * scale:.{decimals}f}"


def best_cells(metrics: Mapping[str, Mapping[str, Any]], key: str, scale: float, decimals: int,
               pick: Any) -> set[str]:
    """The methods whose shown value of ``key`` is the best (ties all count), references excepted
    unless every method is one."""
    contenders = [n for n in metrics if n.split(" ")[0] not in REFERENCES] or list(metrics)
    values = {n: float(shown(metrics[n].get(key), scale, decimals)) for n in contenders
              if shown(metrics[n].get(key), scale, decimals) != "--"}
    if not values:
        return set()
    best = pick(values.values())
    return {n for n, v in values.items() if v == best}


def summary_latex(metrics: Mapping[str, Mapping[str, Any]]) -> str:
    """A booktabs ``tabular`` of ``metrics`` (as in ``metrics.json``), one row per method."""
    best = {key: best_cells(metrics, key, scale, decimals, pick) for _, key, scale, decimals, pick in COLUMNS}
    lines = [
        f"% Success: RTE < {SUCCESS_RTE_M:g} m and RRE < {SUCCESS_RRE_DEG:g} deg; medians over trials with an "
        "estimate; best per column in bold (references none and oracle excepted). Needs \\usepackage{booktabs}.",
        "\\begin{tabular}{l" + "r" * len(COLUMNS) + "}",
        "\\toprule",
        " & ".join(["Method", *(header for header, *_ in COLUMNS)]) + " \\\\",
        "\\midrule",
    ]
    for name, values in metrics.items():
        cells = [escape(name)]
        for _, key, scale, decimals, _ in COLUMNS:
            text = shown(values.get(key), scale, decimals)
            cells.append(f"\\textbf{{{text}}}" if name in best[key] else text)
        lines.append(" & ".join(cells) + " \\\\")
    lines += ["\\bottomrule", "\\end{tabular}"]
    return "\n".join(lines) + "\n"
