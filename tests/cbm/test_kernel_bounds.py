"""CBM's numba kernels never index out of bounds: they run here with numba's bounds checking on
(``NUMBA_BOUNDSCHECK=1``, compiled afresh in a subprocess), on scenes made to reach the edges of
the grids and the candidate sets, on one thread and then on four with every hand-over taken."""
import os
import subprocess
import sys
from pathlib import Path

SCRIPT = r"""
import numpy as np
from cbm import CBMParams, match, se2

def boxes(xy, rng):
    out = np.zeros((len(xy), 7))
    out[:, :2] = xy
    out[:, 3:6] = (4.5, 1.9, 1.6)
    out[:, 6] = rng.uniform(-np.pi, np.pi, len(xy))
    return out

rng = np.random.default_rng(0)
scenes = [
    (rng.uniform(-900, 900, (40, 2)), rng.uniform(-3, 3, (40, 2))),
    (rng.uniform(-3, 3, (40, 2)), rng.uniform(-900, 900, (40, 2))),
    (np.vstack([rng.uniform(-5, 5, (20, 2)), rng.uniform(700, 710, (20, 2))]), rng.uniform(-400, 400, (30, 2))),
    (np.zeros((6, 2)), np.zeros((6, 2))),
    (rng.uniform(-60, 60, (1, 2)), rng.uniform(-60, 60, (5, 2))),
    (rng.uniform(-60, 60, (160, 2)), rng.uniform(-60, 60, (150, 2))),
]
from cbm.engine import tuning

for threads, threshold in ((1, float("inf")), (4, 0)):
    tuning.THREADS = threads
    for name in tuning.THRESHOLDS:
        setattr(tuning, name, threshold)
    for ego_xy, cav_xy in scenes:
        for params in (CBMParams(), CBMParams(consensus_rule="paper", sigma3=3.0), CBMParams(consensus=False),
                       CBMParams(heading="fold")):
            match(boxes(ego_xy, rng), boxes(cav_xy, rng), se2.make(3.0, 3.0, 0.1), params)
print("ok")
"""


def test_the_kernels_stay_in_bounds(tmp_path):
    env = {**os.environ, "NUMBA_BOUNDSCHECK": "1", "NUMBA_CACHE_DIR": str(tmp_path)}
    done = subprocess.run([sys.executable, "-c", SCRIPT], cwd=Path(__file__).resolve().parents[2], env=env,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0 and done.stdout.strip().endswith("ok"), done.stderr[-2000:]
