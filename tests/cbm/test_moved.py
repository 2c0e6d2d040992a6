"""The method package stands alone, and the names that moved out of it keep working for one release."""
from __future__ import annotations

import importlib
import subprocess
import sys

import pytest

from cbm.moved import MOVED


def test_importing_the_method_pulls_in_no_web_server_dataset_reader_table_library_or_ray() -> None:
    code = ("import sys; from cbm import CBMParams, match; "
            "print(' '.join(sorted({m.split('.')[0] for m in sys.modules})))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    loaded = set(done.stdout.split())
    assert {"cbm", "numpy"} <= loaded
    assert not loaded & {"evaluation", "loaders", "app", "presets", "viser", "polars", "ray", "matplotlib"}


@pytest.mark.parametrize("old", sorted(MOVED))
def test_an_old_module_name_warns_and_is_the_new_module(old: str) -> None:
    sys.modules.pop(old, None)
    with pytest.warns(DeprecationWarning, match=rf"{old} moved to {MOVED[old]}"):
        alias = importlib.import_module(old)
    new = importlib.import_module(MOVED[old])
    assert alias is new and new.__spec__.name == MOVED[old]


def test_a_script_of_the_old_release_runs_and_is_told_where_the_names_went() -> None:
    code = ("from cbm.metrics import evaluate\nfrom cbm.scenario import ScenarioParams, make_trial\n"
            "import evaluation.metrics, evaluation.scenario\n"
            "assert evaluate is evaluation.metrics.evaluate and make_trial is evaluation.scenario.make_trial\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "cbm.metrics moved to evaluation.metrics" in done.stderr
    assert "cbm.scenario moved to evaluation.scenario" in done.stderr
