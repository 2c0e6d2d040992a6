"""The method package stands alone: a notebook can run ``cbm.match`` without the app's or the
evaluation's dependencies."""
from __future__ import annotations

import subprocess
import sys


def test_importing_the_method_pulls_in_no_web_server_dataset_reader_table_library_or_ray() -> None:
    code = ("import sys; from cbm import CBMParams, match; "
            "print(' '.join(sorted({m.split('.')[0] for m in sys.modules})))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    loaded = set(done.stdout.split())
    assert {"cbm", "numpy"} <= loaded
    assert not loaded & {"evaluation", "loaders", "app", "presets", "viser", "polars", "ray", "matplotlib"}
