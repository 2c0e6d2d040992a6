"""Plots of an evaluation, read from the per-trial rows: the paper's SIND figure (precision against
eta) and its OPV2V figure (RRE and RTE distributions)."""
from __future__ import annotations

import math
import textwrap
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from evaluation.metric_registry import RUN_METRICS, TRIAL_METRICS  # noqa: E402
from evaluation.sweep import Sweep, summarise  # noqa: E402

from .report import _ranges, fmt, init_name, levels  # noqa: E402

LOG_FLOOR = 1e-3
"""RRE (deg) and RTE (m) below this are drawn at it on the log-scale plot."""
MARKERS = "osD^vP*Xh<>"


def run_title(sources: list[tuple[str, list[int]]], protocol: str) -> str:
    """What a run's plots show, for their title: each dataset with its frames, and the protocol."""
    return "; ".join(_frames_words(name, sorted(set(frames))) for name, frames in sources) + f" · protocol {protocol}"


def _frames_words(name: str, frames: list[int]) -> str:
    return f"{name}, {len(frames)} frame{'s' * (len(frames) != 1)} ({_ranges(frames)})"


def titled(fig: plt.Figure, title: str) -> plt.Figure:
    """``fig`` with ``title`` above its panels (wrapped to the figure's width), laid out again."""
    width = max(40, int(fig.get_figwidth() * 12))
    fig.suptitle("\n".join(textwrap.wrap(title, width)), fontsize=9)
    fig.tight_layout()
    return fig


def plot_precision_vs_eta(rows: list[dict[str, Any]], variants: list[str], sweep: Sweep) -> plt.Figure:
    """The paper's SIND figure: precision against eta, one panel per noise level, one line per method
    (one column per value of the last noise parameter of the grid when it has at most 5)."""
    by = levels(sweep)
    precision = RUN_METRICS["precision"]
    keyed = [{**row, "variant": v} for row, v in zip(rows, variants)]
    stats = summarise(keyed, [*by, "variant", "eta"])
    panels = list(dict.fromkeys(key[:-2] for key, _ in stats))
    last = len(sweep.grid[by[-1]]) if by else 1
    columns = last if last <= 5 else min(len(panels), 4)
    n_rows = math.ceil(len(panels) / columns)
    fig, axes = plt.subplots(n_rows, columns, figsize=(3.6 * columns, 3.2 * n_rows), sharey=True, squeeze=False)
    for ax, panel in zip(axes.flat, panels):
        for k, variant in enumerate(dict.fromkeys(variants)):
            points = [(key[-1], a[precision.key] * precision.unit.scale) for key, a in stats
                      if key[:-2] == panel and key[-2] == variant]
            ax.plot(*zip(*points), marker=MARKERS[k % len(MARKERS)], markerfacecolor="none", label=variant)
        ax.set_title(", ".join(f"{n}={fmt(v)}" for n, v in zip(by, panel)) or "all trials", fontsize=9)
        ax.set_xlabel("co-visibility rate eta")
        ax.grid(alpha=0.3)
    for ax in axes.flat[len(panels):]:
        ax.set_visible(False)
    for ax in axes[:, 0]:
        ax.set_ylabel(precision.heading)
    axes.flat[0].legend(fontsize=8)
    fig.tight_layout()
    return fig


def plot_rre_rte(rows: list[dict[str, Any]], variants: list[str]) -> plt.Figure:
    """The paper's OPV2V figure: RRE and RTE distributions per method (trials with an estimate) and
    of the uncalibrated ``init`` (``report.init_name``, unless the method ``none`` shows it), on a log scale."""
    names = list(dict.fromkeys(variants))
    first = [row for row, v in zip(rows, variants) if v == names[0]]
    fig, axes = plt.subplots(1, 2, figsize=(10.0, 3.8))
    for ax, metric in zip(axes, (TRIAL_METRICS["rre"], TRIAL_METRICS["rte"])):
        data = [[row[metric.key] for row, v in zip(rows, variants) if v == name and row["estimated"]] for name in names]
        ticks = list(names)
        if "none" not in names:
            data.append([row[f"init_{metric.key}"] for row in first])
            ticks.append(init_name(rows))
        ax.boxplot([[max(x, LOG_FLOOR) for x in d] or [math.nan] for d in data], showfliers=True)
        ax.set_xticks(range(1, len(data) + 1), ticks, rotation=30, ha="right", fontsize=8)
        ax.set_yscale("log")
        ax.set_ylabel(f"{metric.label} ({metric.unit.text}, below {LOG_FLOOR:g} drawn at {LOG_FLOOR:g})", fontsize=8)
        ax.grid(alpha=0.3, axis="y")
    fig.tight_layout()
    return fig


def plot_success_curve(curve: list[tuple[float, dict[str, float]]]) -> plt.Figure:
    """Success rate against the error threshold t (RTE < t m and RRE < t deg), one line per method."""
    names = list(curve[0][1]) if curve else []
    fig, ax = plt.subplots(figsize=(6.0, 4.0))
    for k, name in enumerate(names):
        ax.plot([t for t, _ in curve], [rates[name] * 100 for _, rates in curve],
                marker=MARKERS[k % len(MARKERS)], markerfacecolor="none", label=name)
    ax.set_xlabel("threshold t: RTE < t m and RRE < t deg")
    ax.set_ylabel("success rate (%)")
    ax.set_ylim(-2, 102)
    ax.grid(alpha=0.3)
    if names:
        ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def plot_differences(differences: dict[str, dict[str, float]], keys: list[str], lower_better: set[str],
                     title: str) -> plt.Figure:
    """One bar panel per metric key: each method's difference (run B minus run A), green where B is
    better (lower for the keys in ``lower_better``), red where worse, grey where not measured."""
    names = list(differences)
    fig, axes = plt.subplots(1, len(keys), figsize=(2.6 * len(keys) + 1.0, 3.6), squeeze=False)
    for ax, key in zip(axes.flat, keys):
        values = [differences[n].get(key, math.nan) for n in names]
        sign = -1.0 if key in lower_better else 1.0
        colours = ["tab:gray" if math.isnan(v) or v == 0 else "tab:green" if sign * v > 0 else "tab:red"
                   for v in values]
        ax.bar(range(len(names)), [0.0 if math.isnan(v) else v for v in values], color=colours)
        ax.axhline(0.0, color="black", linewidth=0.8)
        ax.set_xticks(range(len(names)), names, rotation=30, ha="right", fontsize=8)
        ax.set_title(key, fontsize=9)
        ax.grid(alpha=0.3, axis="y")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig
