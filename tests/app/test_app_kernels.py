"""CBM's compiled kernels at server start: a subprocess fills numba's on-disk cache while the server
starts, the first frames run interpreted meanwhile and say so, and no CBM time includes the
compile. Also the status line's progress reports."""
from __future__ import annotations

import re
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from app.session import kernels as kernels_module
from app.session.kernels import COMPILING, Kernels
from app.session.progress import announced
from cbm import CBMParams, match
from cbm.warmup import VARIANTS, scene, warm_up
from support import browser as ui

REPO = Path(__file__).resolve().parents[2]


def test_warm_up_calls_match_once_per_variant() -> None:
    seen = []
    seconds = warm_up(report=lambda params, spent: seen.append(params))
    assert seen == list(VARIANTS) and seconds > 0


def test_the_kernels_get_ready_when_the_subprocess_cannot_run(monkeypatch: pytest.MonkeyPatch,
                                                              tmp_path: Path) -> None:
    monkeypatch.setattr(sys, "executable", str(tmp_path / "no-such-python"))
    monkeypatch.setattr(kernels_module, "kernels_cached", lambda baselines=False: False)
    kernels = Kernels()
    assert kernels.wait(timeout=300)
    assert kernels.compile_seconds is None and kernels.load_seconds is not None


def test_a_frame_runs_interpreted_while_the_kernels_compile(monkeypatch: pytest.MonkeyPatch) -> None:
    """Not ready: ``running`` runs CBM interpreted, with the compiled results; once the compile
    ends the waiting callbacks run and CBM runs compiled."""
    release, called = threading.Event(), []
    monkeypatch.setattr(kernels_module, "compile_side_by_side", lambda *args, **kwargs: release.wait(60) and 0.0)
    monkeypatch.setattr(kernels_module, "kernels_cached", lambda baselines=False: False)
    kernels = Kernels()
    ego, cav, init = scene()
    expected = match(ego, cav, init, CBMParams())
    with kernels.running() as interpreting:
        result = match(ego, cav, init, CBMParams())
    kernels.when_ready(lambda: called.append(True))
    assert interpreting and not kernels.ready and called == []
    assert np.array_equal(result.pairs, expected.pairs) and np.array_equal(result.transform, expected.transform)
    release.set()
    assert kernels.wait(timeout=120)
    with kernels.running() as interpreting:
        assert not interpreting
    assert called == [True]


def test_the_baselines_kernels_compile_after_cbms_in_a_subprocess_and_their_methods_wait(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 47 item 7: FreeAlign's kernels took 12.5 s to compile on its first use, inside a tab's
    recompute. They compile in a process of their own once CBM's are ready; until then the methods
    that run them are not ready, and their callbacks wait. Only this test's ``Kernels`` is heard: one
    an earlier test made may still be preparing on its thread, on a busy machine."""
    asked, release, called, made, ours = [], threading.Event(), [], threading.Event(), []

    def compiling(processes, timeout=None, parts=("matching", "selection")):
        made.wait(60)
        if processes is not ours[0]:
            return 0.0
        asked.append(tuple(parts))
        if parts == kernels_module.BASELINE_PARTS:
            release.wait(60)
        return 0.0

    monkeypatch.setattr(kernels_module, "compile_side_by_side", compiling)
    monkeypatch.setattr(kernels_module, "kernels_cached", lambda baselines=False: False)
    kernels = Kernels()
    ours.append(kernels._processes)
    made.set()
    assert kernels.wait(timeout=120)
    kernels.when_ready(lambda: called.append("freealign"), method="freealign")
    assert kernels.ready_for("cbm") and kernels.ready_for("icp") and not kernels.ready_for("freealign")
    assert kernels.ready_for("v2xregpp") and not kernels.wait(timeout=0.1, method="freealign") and called == []
    release.set()
    assert kernels.wait(timeout=300, method="freealign")
    assert asked == [("matching", "selection"), kernels_module.BASELINE_PARTS] and called == ["freealign"]
    assert kernels.baseline_seconds is not None


def test_the_cache_is_found_filled_or_empty(tmp_path: Path) -> None:
    """``kernels_cached`` in a new process: False on an empty cache, True once ``--part`` filled both halves."""
    env = {"NUMBA_CACHE_DIR": str(tmp_path), "PATH": "/usr/bin:/bin"}
    asked = [sys.executable, "-c", "from cbm.warmup import kernels_cached; print(kernels_cached())"]
    before = subprocess.run(asked, cwd=REPO, env=env, capture_output=True, text=True, check=True).stdout.split()
    for part in ("matching", "selection"):
        subprocess.run([sys.executable, "-m", "cbm.warmup", "--part", part], cwd=REPO, env=env, check=True,
                       capture_output=True)
    after = subprocess.run(asked, cwd=REPO, env=env, capture_output=True, text=True, check=True).stdout.split()
    assert (before, after) == (["False"], ["True"])


def test_cbms_cache_is_found_without_the_baselines_and_theirs_apart(tmp_path: Path) -> None:
    """CBM's kernels found cached whether the baselines' are or not (before, a FreeAlign never run
    made every start compile CBM's again), and the baselines' found once their part filled them."""
    env = {"NUMBA_CACHE_DIR": str(tmp_path), "PATH": "/usr/bin:/bin"}
    asked = [sys.executable, "-c", "import cbm.methods; from cbm.warmup import kernels_cached; "
             "print(kernels_cached(), kernels_cached(baselines=True))"]

    def found() -> list[str]:
        return subprocess.run(asked, cwd=REPO, env=env, capture_output=True, text=True, check=True).stdout.split()

    for part in ("matching", "selection"):
        subprocess.run([sys.executable, "-m", "cbm.warmup", "--part", part], cwd=REPO, env=env, check=True,
                       capture_output=True)
    halves = found()
    subprocess.run([sys.executable, "-m", "cbm.warmup", "--part", "baselines"], cwd=REPO, env=env, check=True,
                   capture_output=True)
    assert (halves, found()) == (["True", "False"], ["True", "True"])


def test_a_slow_block_is_announced_until_it_ends_and_a_quick_one_not_at_all() -> None:
    said: list[float] = []
    with announced(said.append, after=0.05, every=0.05):
        time.sleep(0.4)
    count = len(said)
    time.sleep(0.2)
    assert count >= 3 and len(said) == count and said == sorted(said)
    quick: list[float] = []
    with announced(quick.append, after=0.5):
        pass
    assert quick == []



def test_blocks_announced_at_once_each_get_their_own_reports_and_a_failing_one_stops_alone() -> None:
    """One thread makes every block's reports: two blocks at once both report (until each ends), and a
    report that raises ends that block's reports only."""
    first, second, broken = [], [], []
    reported = threading.Event()

    def failing(seconds: float) -> None:
        broken.append(seconds)
        raise RuntimeError("report failed")

    def counted(seconds: float) -> None:
        second.append(seconds)
        if len(second) >= 3:
            reported.set()

    with announced(first.append, after=0.01, every=0.01), announced(failing, after=0.01, every=0.01):
        with announced(counted, after=0.02, every=0.01):
            assert reported.wait(10)
        count = len(second)
        while len(first) < 3:
            time.sleep(0.01)
    ended = len(first)
    time.sleep(0.1)
    assert len(second) == count and len(first) == ended and len(broken) == 1
    assert first == sorted(first) and second == sorted(second)


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


@pytest.mark.browser
@ui.requires_chromium
def test_a_fresh_start_compiles_off_the_clock(browser, tmp_path: Path) -> None:
    """With an empty numba cache the first frame is shown while the kernels compile, said so
    beside the interpreted CBM time (shorter than the compile); once compiled, the frame again with a
    CBM time of milliseconds and the compile time apart."""
    port = _free_port()
    env = {"CBM_EXPLORER_PRESETS": str(tmp_path), "NUMBA_CACHE_DIR": str(tmp_path / "numba"), "PATH": "/usr/bin:/bin"}
    process = subprocess.Popen([sys.executable, "serve.py", "--port", str(port), "--dataset", "synthetic:60"],
                               cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, env=env)
    watchdog = threading.Timer(300, process.kill)
    watchdog.start()
    try:
        assert any(line.startswith("CBM Explorer on") for line in process.stdout)
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.goto(f"http://127.0.0.1:{port}")
        page.get_by_text(COMPILING).wait_for(timeout=120_000)
        first = re.search(r"CBM time\s+([\d.]+) ms", ui.metrics(page))
        note = page.get_by_text(re.compile("CBM's kernels compiled in")).inner_text(timeout=240_000)
        compiled = float(re.search(r"compiled in ([\d.]+) s", note).group(1))
        shown = re.search(r"CBM time\s+([\d.]+) ms", ui.metrics(page))
        assert compiled > 1.0 and float(shown.group(1)) < 1000.0, (note, shown.group(0))
        assert float(first.group(1)) < 1000.0 * compiled, (first.group(0), note)
        page.close()
    finally:
        watchdog.cancel()
        process.terminate()
        process.wait(timeout=10)
