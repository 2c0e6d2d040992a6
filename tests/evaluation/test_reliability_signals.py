"""Stop signals that always stop (issue 27): during evaluate.py's imports, and when the main thread
cannot run its handler (``evaluation.stop.Watchdog``)."""
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from support.processes import alive, descendants, has_loaded, wait_for

REPO = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM])
def test_a_stop_signal_while_evaluate_py_imports_is_one_line(tmp_path, signum: int) -> None:
    process = subprocess.Popen([sys.executable, str(REPO / "evaluate.py"), "--dataset", "synthetic:5", "--frames",
                                "0", "--out", str(tmp_path / "out")], cwd=REPO, stderr=subprocess.PIPE, text=True)
    wait_for(lambda: has_loaded(process.pid, "numpy") or process.poll() is not None, 60, "numpy being imported")
    process.send_signal(signum)
    stderr = process.communicate(timeout=60)[1]
    name = signal.Signals(signum).name
    assert process.returncode == 128 + signum, stderr
    lines = stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"evaluate.py: stopped by {name}"), stderr
    assert not (tmp_path / "out").exists()


def test_the_watchdog_ends_a_process_whose_main_thread_does_not_stop(tmp_path) -> None:
    """SIGTERM's handler replaced by one that returns (as a third-party start-up may replace it), the
    main thread waiting on a lock for ever: the watchdog ends the process, and its child, within 2 s."""
    script = tmp_path / "stuck.py"
    script.write_text(
        "import signal, subprocess, sys, threading\n"
        "from evaluation.stop import Watchdog\n"
        "Watchdog(lambda name: f'stuck: stopped by {name}')\n"
        "signal.signal(signal.SIGTERM, lambda *_: None)\n"
        "child = subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(600)'])\n"
        "print('ready', flush=True)\n"
        "lock = threading.Lock()\n"
        "lock.acquire()\n"
        "lock.acquire()\n")
    process = subprocess.Popen([sys.executable, str(script)], cwd=REPO, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    assert process.stdout.readline().strip() == "ready"
    children = descendants(process.pid)
    assert children
    started = time.monotonic()
    process.send_signal(signal.SIGTERM)
    stderr = process.communicate(timeout=60)[1]
    assert time.monotonic() - started < 30, "the watchdog did not end the stuck process"
    assert process.returncode == 143 and stderr.strip() == "stuck: stopped by SIGTERM"
    wait_for(lambda: not any(alive(child) for child in children), 10, "the child to be gone")


def test_killed_children_are_reaped_not_left_defunct() -> None:
    """A stop kills this process's children; each stayed listed as ``<defunct>`` until its parent
    waited for it (seen 1.5 s after a stop, issue 40, item 7)."""
    from evaluation.stop import reap

    children = [subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"]) for _ in range(2)]
    for child in children:
        os.kill(child.pid, signal.SIGKILL)
    reap({child.pid for child in children})
    for child in children:
        assert not Path(f"/proc/{child.pid}").exists(), f"{child.pid} is still listed"
