"""Evaluation of calibration methods on datasets, in the spirit of evo: running gives a per-trial
table, reports and plots read it, the command line is thin.

    import evaluation
    table = evaluation.run(["argoverse2"], methods=("cbm", "oracle"), grid={"sigma_p": (0.3, 0.6)}, seed=0)

Modules: ``run`` (datasets and a sweep into the table), ``metric_registry`` (every metric reported,
one object each), ``report`` (Markdown summary),
``aggregates`` (``metrics.json`` and the success curve), ``latex`` (``summary.tex``), ``plots`` (the
paper's figures), ``outputs`` (the files, written atomically), ``compare`` (two runs' differences),
``cli`` (``evaluate.py`` and ``evaluate.py compare``).
"""
from .run import DEFAULT_METHODS, Plan, Source, plan, run, run_plan, trial_table, without_timing

__all__ = ["DEFAULT_METHODS", "Plan", "Source", "plan", "run", "run_plan", "trial_table", "without_timing"]
