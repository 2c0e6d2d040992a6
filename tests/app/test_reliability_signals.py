"""A stop signal while ``serve.py`` starts (issue 27, row 15): it acts while the dataset loads, not
after, with one line, status 128 + the signal and no process left behind; a stopped server ends
whatever its workers are doing (issue 40)."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import polars as pl
import pytest

import loaders
from support.processes import alive, descendants, has_loaded, wait_for

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def slow_dataset(tmp_path_factory) -> tuple[Path, float]:
    """A table of 20,000 frames of 200 vehicles (160 MB), and the seconds it takes to load here and
    now (about 7 s on a quiet machine, more on a busy one): several times the watchdog's grace."""
    frames, objects = 20_000, 200
    rng = np.random.default_rng(0)
    table = pl.DataFrame({
        "frame": np.repeat(np.arange(frames), objects),
        "track_id": np.tile([f"v{k}" for k in range(objects)], frames),
        "category": "vehicle",
        "x": rng.uniform(-50, 50, frames * objects).round(2),
        "y": rng.uniform(-50, 50, frames * objects).round(2),
        "length": 4.5, "width": 1.9, "yaw": 0.0,
    })
    path = tmp_path_factory.mktemp("slow") / "slow.csv"
    table.write_csv(path)
    del table
    started = time.monotonic()
    loaders.open(path)
    return path, time.monotonic() - started


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT])
def test_a_stop_signal_while_the_dataset_loads_stops_before_it_has_loaded(slow_dataset, tmp_path,
                                                                           signum: int) -> None:
    dataset, load_seconds = slow_dataset
    empty = str(tmp_path / "numba")  # a filled cache is loaded without compiling subprocesses
    process = subprocess.Popen([sys.executable, "serve.py", "--dataset", str(dataset), "--port", "0"],
                               cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               env={**os.environ, "CBM_EXPLORER_PRESETS": str(tmp_path), "NUMBA_CACHE_DIR": empty})
    wait_for(lambda: descendants(process.pid) or process.poll() is not None, 120,
             "the kernels' compiling subprocesses, started just before the dataset loads")
    children = descendants(process.pid)
    started = time.monotonic()
    process.send_signal(signum)
    stdout, stderr = process.communicate(timeout=120)
    took = time.monotonic() - started
    assert process.returncode == 128 + signum, stderr
    assert stdout == "" and stderr.strip() == f"serve.py: stopped by {signal.Signals(signum).name} while starting"
    assert took < load_seconds / 2, f"stopped after {took:.1f} s; the load takes {load_seconds:.1f} s"
    assert children and not any(alive(child) for child in children)


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_stop_signal_while_serve_py_imports_is_one_line(tmp_path, signum: int) -> None:
    process = subprocess.Popen([sys.executable, "serve.py", "--dataset", "synthetic:5", "--port", "0"], cwd=REPO,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               env={**os.environ, "CBM_EXPLORER_PRESETS": str(tmp_path)})
    wait_for(lambda: has_loaded(process.pid, "numpy") or process.poll() is not None, 120, "numpy being imported")
    process.send_signal(signum)
    stdout, stderr = process.communicate(timeout=120)
    assert process.returncode == 128 + signum, stderr
    lines = stderr.strip().splitlines()
    assert stdout == "" and len(lines) == 1
    assert lines[0].startswith(f"serve.py: stopped by {signal.Signals(signum).name}")


def test_a_stopped_server_ends_within_2_s_whatever_its_workers_are_doing() -> None:
    """After a stop, a tab's worker may be inside a compiled kernel for minutes, where nothing
    interrupts it, and the interpreter would wait for it at exit (issue 40: "Server stopped", then
    200 % CPU, deaf to a second signal). Here a worker that never returns stands in for it."""
    script = ("import threading, time\n"
              "from app import cli\n"
              "threading.Thread(target=lambda: time.sleep(600), name='busy-worker').start()\n"
              "cli._end_soon()\n")
    done = subprocess.run([sys.executable, "-c", script], cwd=REPO, capture_output=True, text=True,
                          timeout=300)  # without the deadline, the worker keeps the process for 600 s
    assert done.returncode == 0, done.stderr
