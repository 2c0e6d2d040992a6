"""Evaluate CBM and the baselines on datasets: a tidy per-trial table, a Table-I-shaped summary and plots
(installed: the ``cbm-evaluate`` command).

    python evaluate.py --dataset argoverse2 --protocol sind --grid eta=0.2,0.6 sigma_p=0,0.3 --out results

The importable package is ``evaluation`` (``evaluation.run`` returns the table); ``python
evaluate.py --help`` lists the options.
"""
import sys

from app.commands import evaluate as main

if __name__ == "__main__":
    sys.exit(main())
