"""The metrics an evaluation reports, one object each: its key, label, unit, which way is better, its
formula (the class docstring, first paragraph) and how it is computed. Every output reads this
registry, so a new metric is one class here and one ``register`` call:

- ``TRIAL_METRICS``, numbers of one trial: columns of ``trials.csv``, the app's worst-frames table
  and ranking, its pinned comparison and its frame panel, the units of the RRE / RTE plot;
- ``RUN_METRICS``, numbers of a method's trials together: ``aggregate``, the rows of ``summary.md``
  and of the app's sequence table, the keys of ``metrics.json``, ``summary.tex`` and ``compare``.

    aggregate([evaluate(result, trial) for result, trial in runs])["rre_median"]

In the style of evo's ``evo.core.metrics``: a metric is computed from each trial's record
(``evaluation.metrics.TrialMetrics``, which ``evaluate`` makes from a result and its trial), and a
run metric is a statistic over those records. A metric with nothing to measure is NaN, never 0.
"""
from __future__ import annotations

import inspect
import math
from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from .metrics import TrialMetrics, is_success

Better = Literal["higher", "lower"]


@dataclass(frozen=True)
class Unit:
    """How a value is stored and shown: ``scale`` turns the stored value into the shown one (a share
    from 0 to 1 into %, seconds into ms), rounded to ``digits`` decimals."""

    text: str
    """In a table's header: ``%``, ``m``, ``deg``, ``ms``; empty for a plain number."""
    suffix: str
    """After a number in the app: `` %``, `` m``, ``°``, `` ms``."""
    scale: float = 1.0
    digits: int = 2

    def shown(self, value: float | None, dash: str = "-", suffix: bool = False) -> str:
        """``value`` scaled and rounded, with the suffix when asked; ``dash`` when it is undefined."""
        if value is None or math.isnan(value):
            return dash
        return f"{value * self.scale:.{self.digits}f}{self.suffix if suffix else ''}"


SHARE = Unit("%", " %", 100.0, 1)
RATIO = Unit("", "")
METRES = Unit("m", " m")
DEGREES = Unit("deg", "°")
PAIRS = Unit("pairs", " pairs", 1.0, 1)
MILLISECONDS = Unit("ms", " ms", 1000.0, 1)
"""Stored in seconds."""
SUCCESS_LEVELS = (1.0, 2.0, 3.0, 4.0, 5.0)
"""Thresholds t of the success rates reported: RTE < t m and RRE < t deg (V2X-Reg++ reports 1 to 5)."""
HEADLINE_LEVEL = 1.0
"""The success test of ``evaluation.metrics.is_success``: its rate is ``success_rate``."""


class Metric(ABC):
    """A metric's key (a column of ``trials.csv``, or a key of ``aggregate``), the label the tables
    show, its unit and which way is better; the class docstring's first paragraph is its formula."""

    key: str
    label: str
    unit: Unit
    better: Better

    @property
    def heading(self) -> str:
        """The label with its unit, as a table's header shows it: ``median RTE (m)``."""
        return f"{self.label} ({self.unit.text})" if self.unit.text else self.label

    @property
    def formula(self) -> str:
        """The first paragraph of the class docstring, on one line."""
        return " ".join((inspect.getdoc(self) or "").split("\n\n")[0].split())


class TrialMetric(Metric):
    """A number of one trial."""

    @abstractmethod
    def of(self, m: TrialMetrics) -> float:
        """The metric of one trial, from its record."""


class RunMetric(Metric):
    """A number of a method's trials together."""

    headline = False
    """In ``summary.tex`` and ``compare.png``."""
    wall_clock = False
    """Measures time: left out with ``--no-timing`` (it differs from run to run)."""

    @property
    def saved_as(self) -> str:
        """Its key in ``metrics.json``."""
        return self.key

    @abstractmethod
    def __call__(self, trials: Sequence[TrialMetrics]) -> float:
        """The metric over ``trials``."""


class RTE(TrialMetric):
    """RTE = ||t_est - t_true||_2 (m): the relative translation error; NaN without an estimate."""

    key, label, unit, better = "rte", "RTE", METRES, "lower"

    def of(self, m: TrialMetrics) -> float:
        return m.rte


class RRE(TrialMetric):
    """RRE = |wrap(yaw(T_est) - yaw(T_true))| (deg), wrapped to [-180, 180): the relative rotation
    error; NaN without an estimate."""

    key, label, unit, better = "rre", "RRE", DEGREES, "lower"

    def of(self, m: TrialMetrics) -> float:
        return m.rre


class Precision(TrialMetric):
    """precision = |M_hat n M| / |M_hat|: the share of the output pairs that are true (paper
    sec. V-B); NaN when nothing was matched."""

    key, label, unit, better = "precision", "precision", RATIO, "higher"

    def of(self, m: TrialMetrics) -> float:
        return m.precision


class Recall(TrialMetric):
    """recall = |M_hat n M| / |M|: the share of the true (co-visible) pairs that were output (paper
    sec. V-B); NaN without true pairs."""

    key, label, unit, better = "recall", "recall", RATIO, "higher"

    def of(self, m: TrialMetrics) -> float:
        return m.recall


class AverageDistance(TrialMetric):
    """AD = 1/|M_hat| sum_{(i,j) in M_hat} ||p_i - p_j||_2 (m): the true distance between the two
    objects of each output pair, 0 for a true pair (paper sec. V-B); NaN when nothing was matched."""

    key, label, unit, better = "ad", "AD", METRES, "lower"

    def of(self, m: TrialMetrics) -> float:
        return m.ad


class Margin(TrialMetric):
    """consensus margin = card of the winning set - card of its strongest rival (pairs): how clearly
    CBM's consensus won (beyond the paper); a method without a consensus reports its pair count
    (nothing rivals it), a result without a margin NaN."""

    key, label, unit, better = "margin", "consensus margin", PAIRS, "higher"

    def of(self, m: TrialMetrics) -> float:
        return m.margin


class LatencyError(TrialMetric):
    """latency error = |d_told - d| (ms): how far the age of the CAV's message a method tells (CBM over
    time) lies from its true age d (a late message, ``evaluation.delay``); NaN where it tells none."""

    key, label, unit, better = "latency_error", "latency error", MILLISECONDS, "lower"

    def of(self, m: TrialMetrics) -> float:
        return m.latency_error_s


class PooledPrecision(RunMetric):
    """precision = sum |M_hat n M| / sum |M_hat| over all trials: micro-averaged, every output pair
    weighs the same whatever its trial (paper Table I); NaN when nothing was matched."""

    key, label, unit, better, headline = "precision", "precision", SHARE, "higher", True

    def __call__(self, trials: Sequence[TrialMetrics]) -> float:
        return _ratio(sum(m.n_correct for m in trials), sum(m.n_matched for m in trials))


class PooledRecall(RunMetric):
    """recall = sum |M_hat n M| / sum |M| over all trials: micro-averaged, every true pair weighs the
    same whatever its trial (paper Table I); NaN without true pairs."""

    key, label, unit, better, headline = "recall", "recall", SHARE, "higher", True

    def __call__(self, trials: Sequence[TrialMetrics]) -> float:
        return _ratio(sum(m.n_correct for m in trials), sum(m.n_true for m in trials))


class PooledDistance(RunMetric):
    """AD = sum_k AD_k |M_hat_k| / sum_k |M_hat_k| over the trials k (m): the mean true distance
    between the two objects of every output pair of the run."""

    key, label, unit, better = "ad", "AD", METRES, "lower"

    def __call__(self, trials: Sequence[TrialMetrics]) -> float:
        return _ratio(sum(m.ad * m.n_matched for m in trials if m.n_matched), sum(m.n_matched for m in trials))


class Median(RunMetric):
    """median X = the median of a trial metric X over the trials where it is defined (RRE and RTE:
    the trials with an estimate)."""

    word = "median"

    def __init__(self, metric: TrialMetric, headline: bool = False) -> None:
        self.metric, self.headline = metric, headline
        self.key, self.label = f"{metric.key}_{self.word}", f"{self.word} {metric.label}"
        self.unit, self.better = metric.unit, metric.better

    @property
    def saved_as(self) -> str:
        return f"{self.word}_{self.metric.key}"

    def __call__(self, trials: Sequence[TrialMetrics]) -> float:
        values = np.array([self.metric.of(m) for m in trials], dtype=float)
        values = values[~np.isnan(values)]
        return float(self.statistic(values)) if len(values) else math.nan

    @staticmethod
    def statistic(values: np.ndarray) -> float:
        return float(np.median(values))


class Mean(Median):
    """mean X = the mean of a trial metric X over the trials where it is defined (RRE and RTE: the
    trials with an estimate)."""

    word = "mean"

    @staticmethod
    def statistic(values: np.ndarray) -> float:
        return float(values.mean())


class SuccessRate(RunMetric):
    """success @ t = the share of all trials whose pose was estimated with RTE < t m and RRE < t deg
    (a trial without an estimate fails)."""

    unit, better = SHARE, "higher"

    def __init__(self, level: float) -> None:
        self.level, self.headline = level, level == HEADLINE_LEVEL
        self.key = "success_rate" if self.headline else f"success_rate_{level:g}"
        self.label = f"success @ {level:g} m, {level:g} deg"

    def __call__(self, trials: Sequence[TrialMetrics]) -> float:
        return _ratio(sum(is_success(m, rte_max=self.level, rre_max=self.level) for m in trials), len(trials))


class MeanOfSuccesses(RunMetric):
    """mX @ t = the mean of a trial metric X over the trials that succeed at t (RTE < t m and RRE <
    t deg): V2X-Reg++'s mRRE and mRTE beside its success rates; NaN when no trial succeeds."""

    def __init__(self, metric: TrialMetric, level: float) -> None:
        self.metric, self.level, self.unit, self.better = metric, level, metric.unit, metric.better
        self.key, self.label = f"m{metric.key}@{level:g}", f"m{metric.label} of successes @ {level:g} m, {level:g} deg"

    def __call__(self, trials: Sequence[TrialMetrics]) -> float:
        values = [self.metric.of(m) for m in trials if is_success(m, rte_max=self.level, rre_max=self.level)]
        return float(np.mean(values)) if values else math.nan


class AbstainRate(RunMetric):
    """abstained = the share of the trials on which the method said its pose has not enough evidence
    (``cbm.MatchResult.abstained``; that pose is still scored)."""

    key, label, unit, better = "abstain_rate", "abstained", SHARE, "lower"

    def __call__(self, trials: Sequence[TrialMetrics]) -> float:
        return _ratio(sum(m.abstained for m in trials), len(trials))


class ReturnedSuccess(RunMetric):
    """success where not abstained = success @ 1 over the trials the method did not abstain on: how
    far its answers can be trusted."""

    key, label, unit, better = "returned_success", "success where not abstained", SHARE, "higher"

    def __call__(self, trials: Sequence[TrialMetrics]) -> float:
        returned = [m for m in trials if not m.abstained]
        return _ratio(sum(is_success(m) for m in returned), len(returned))


class MedianRuntime(RunMetric):
    """median runtime = the median over the trials of the method's wall-clock time
    (``result.timings["total"]``), where it has one."""

    key, label, unit, better, wall_clock = "runtime_median_s", "median runtime", MILLISECONDS, "lower", True

    @property
    def saved_as(self) -> str:
        return "median_runtime_s"

    def __call__(self, trials: Sequence[TrialMetrics]) -> float:
        values = [m.runtime_s for m in trials if not math.isnan(m.runtime_s)]
        return float(np.median(values)) if values else math.nan


TRIAL_METRICS: dict[str, TrialMetric] = {}
"""Every trial metric by key, in the order the app's per-frame tables show them."""
RUN_METRICS: dict[str, RunMetric] = {}
"""Every run metric by key, in the order of ``summary.md``'s rows (the paper's Table I first)."""


def register(metric: Metric) -> Metric:
    """Add ``metric`` to ``TRIAL_METRICS`` or ``RUN_METRICS`` (after the ones there); ``ValueError``
    when its key is taken."""
    registry: dict = TRIAL_METRICS if isinstance(metric, TrialMetric) else RUN_METRICS
    if metric.key in registry:
        raise ValueError(f"a metric with key {metric.key!r} is already registered: {registry[metric.key].label}")
    registry[metric.key] = metric
    return metric


def run_metrics(timing: bool = True) -> list[RunMetric]:
    """The run metrics in order; without ``timing``, those that measure time left out."""
    return [metric for metric in RUN_METRICS.values() if timing or not metric.wall_clock]


def aggregate(trials: Sequence[TrialMetrics]) -> dict[str, float]:
    """The counts ``n_trials`` and ``n_estimated`` (trials with a pose estimate), then every metric
    of ``RUN_METRICS`` over ``trials``, by key."""
    counts = {"n_trials": float(len(trials)), "n_estimated": float(sum(m.estimated for m in trials))}
    return {**counts, **{key: metric(trials) for key, metric in RUN_METRICS.items()}}


def _ratio(numerator: float, denominator: float) -> float:
    return float(numerator) / float(denominator) if denominator else math.nan


for _metric in (RTE(), RRE(), Precision(), Recall(), AverageDistance(), Margin(),
                PooledPrecision(), PooledRecall(), PooledDistance(), Median(RRE(), headline=True),
                Median(RTE(), headline=True), Mean(RRE()), Mean(RTE()),
                *(m for t in SUCCESS_LEVELS for m in (SuccessRate(t), MeanOfSuccesses(RRE(), t),
                                                      MeanOfSuccesses(RTE(), t))),
                AbstainRate(), ReturnedSuccess(), Median(Margin()), MedianRuntime(), LatencyError(),
                Median(LatencyError())):
    register(_metric)
