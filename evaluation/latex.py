"""The summary as a LaTeX table for papers (``summary.tex``, booktabs): one row per method, one
column per headline run metric (``evaluation.metric_registry``: precision, recall, median RRE and
RTE, success rate), the best of each column in bold."""
from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from .metric_registry import RunMetric, run_metrics

REFERENCES = ("none", "oracle")
"""Reference methods: shown, but not in the running for best (oracle has the true pairs)."""
SPECIAL = {"\\": "\\textbackslash{}", "&": "\\&", "%": "\\%", "$": "\\$", "#": "\\#", "_": "\\_",
           "{": "\\{", "}": "\\}", "~": "\\textasciitilde{}", "^": "\\textasciicircum{}"}


def escape(text: str) -> str:
    """``text`` with LaTeX's special characters escaped."""
    return "".join(SPECIAL.get(c, c) for c in text)


def shown(value: Any, metric: RunMetric) -> str:
    """The cell text of a value: scaled and rounded in the metric's unit, ``--`` when nothing was measured."""
    return metric.unit.shown(value, dash="--")


def best_cells(metrics: Mapping[str, Mapping[str, Any]], metric: RunMetric) -> set[str]:
    """The methods whose shown value of ``metric`` is the best (ties all count), references excepted
    unless every method is one."""
    contenders = [n for n in metrics if n.split(" ")[0] not in REFERENCES] or list(metrics)
    values = {n: float(shown(metrics[n].get(metric.saved_as), metric)) for n in contenders
              if shown(metrics[n].get(metric.saved_as), metric) != "--"}
    if not values:
        return set()
    best = (max if metric.better == "higher" else min)(values.values())
    return {n for n, v in values.items() if v == best}


def summary_latex(metrics: Mapping[str, Mapping[str, Any]]) -> str:
    """A booktabs ``tabular`` of ``metrics`` (as in ``metrics.json``), one row per method, one column
    per headline run metric."""
    columns = [metric for metric in run_metrics() if metric.headline]
    best = {metric.key: best_cells(metrics, metric) for metric in columns}
    lines = [
        "% Metrics as defined in summary.md; best per column in bold (references none and oracle excepted). "
        "Needs \\usepackage{booktabs}.",
        "\\begin{tabular}{l" + "r" * len(columns) + "}",
        "\\toprule",
        " & ".join(["Method", *(escape(metric.heading) for metric in columns)]) + " \\\\",
        "\\midrule",
    ]
    for name, values in metrics.items():
        cells = [escape(name)]
        for metric in columns:
            text = shown(values.get(metric.saved_as), metric)
            cells.append(f"\\textbf{{{text}}}" if name in best[metric.key] else text)
        lines.append(" & ".join(cells) + " \\\\")
    lines += ["\\bottomrule", "\\end{tabular}"]
    return "\n".join(lines) + "\n"
