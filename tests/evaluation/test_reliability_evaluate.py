"""evaluate.py under faults and bad input: a stop signal ends it at once with no orphan and no
partial file, ``--out`` is checked before the run, a failed run keeps the older run's files whole."""
import multiprocessing
import os
import signal
import subprocess
import sys
import threading
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import pytest

import evaluation.cli
import evaluation.outputs
from evaluation.executors import stop_pool

REPO = Path(__file__).resolve().parents[2]
QUICK = ["--dataset", "synthetic:40", "--frames", "0:2", "--methods", "icp", "--workers", "1"]
LONG = ["--dataset", "synthetic:100", "--workers", "2"]
"""A run of a minute or more on two cores: long enough to be stopped midway."""


def children(pid: int) -> list[int]:
    """The processes whose parent is ``pid`` (from /proc)."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                found.append(int(entry.name))
    return found


def workers(pid: int) -> list[int]:
    """The process pool's workers among the children of ``pid``."""
    found = []
    for child in children(pid):
        try:
            if b"spawn_main" in Path(f"/proc/{child}/cmdline").read_bytes():
                found.append(child)
        except OSError:
            continue
    return found


def alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def wait_for(condition, timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.05)


def contents(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def leftovers(out: Path) -> list[str]:
    return sorted(p.name for p in out.parent.iterdir() if p.name.startswith(f".{out.name}."))


@pytest.fixture
def old_run(tmp_path) -> Path:
    """``--out`` holding a previous run's complete files (with summary.tex)."""
    out = tmp_path / "results"
    assert evaluation.cli.main([*QUICK, "--latex", "--out", str(out)]) == 0
    return out


@pytest.mark.parametrize("signum, group", [(signal.SIGTERM, False), (signal.SIGINT, True)],
                         ids=["SIGTERM to the process", "Ctrl-C to the process group"])
def test_a_stop_signal_midway_ends_the_run_with_no_orphan_and_no_partial_file(old_run, signum, group):
    """Ctrl-C reaches the pool's workers too: they ignore it, so the one line is the parent's."""
    before = contents(old_run)
    run = subprocess.Popen([sys.executable, "evaluate.py", *LONG, "--out", str(old_run)], cwd=REPO,
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        wait_for(lambda: len(workers(run.pid)) >= 2, 120, "the pool's two workers")
        spawned = children(run.pid)
        time.sleep(1.0)
        assert run.poll() is None, run.stderr.read()
        os.killpg(run.pid, signum) if group else run.send_signal(signum)
        stopped = time.monotonic()
        run.wait(timeout=60)
        assert time.monotonic() - stopped < 30, "the run went on instead of stopping midway (it takes a minute or more)"
    finally:
        run.kill()
    stdout, stderr = run.communicate()
    name = signal.Signals(signum).name
    assert run.returncode == 128 + signum
    assert stderr == f"evaluate.py: stopped by {name}; nothing written\n" and stdout == ""
    wait_for(lambda: not any(alive(p) for p in spawned), 1, "the workers to end")
    assert contents(old_run) == before and leftovers(old_run) == []


def test_an_unwritable_out_is_one_line_before_anything_is_loaded(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(evaluation.cli, "plan", lambda *a, **k: pytest.fail("the datasets were loaded"))
    (tmp_path / "a-file").write_text("not a folder")
    with pytest.raises(SystemExit) as stop:
        evaluation.cli.main([*QUICK, "--out", str(tmp_path / "a-file" / "results")])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1
    assert err.startswith("evaluate.py: error: --out:") and "a-file is a file" in err


def test_the_command_refuses_an_unwritable_out_in_one_line(tmp_path):
    (tmp_path / "a-file").write_text("not a folder")
    done = subprocess.run([sys.executable, "evaluate.py", *QUICK, "--out", str(tmp_path / "a-file" / "x")],
                          cwd=REPO, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and done.stderr.count("\n") == 1 and "a-file is a file" in done.stderr


def test_a_folder_with_other_files_is_refused_not_replaced(tmp_path, capsys):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("the user's work")
    with pytest.raises(SystemExit) as stop:
        evaluation.cli.main([*QUICK, "--out", str(out)])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1 and "'notes.txt'" in err
    assert contents(out) == {"notes.txt": b"the user's work"} and leftovers(out) == []


def test_a_failed_write_keeps_the_older_run_whole_and_leaves_no_staging_folder(old_run, capsys, monkeypatch):
    before = contents(old_run)

    def disk_full(*args):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(evaluation.outputs, "plot_success_curve", disk_full)
    assert evaluation.cli.main([*QUICK, "--methods", "cbm", "--out", str(old_run)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "No space left on device" in err and "untouched" in err
    assert contents(old_run) == before and leftovers(old_run) == []


def test_a_new_run_replaces_every_file_of_the_older_one(old_run):
    assert "summary.tex" in contents(old_run)
    assert evaluation.cli.main([*QUICK, "--methods", "cbm", "--out", str(old_run)]) == 0
    assert "summary.tex" not in contents(old_run) and "| cbm |" in (old_run / "summary.md").read_text()
    assert leftovers(old_run) == []


def test_a_dataset_without_objects_is_one_line_and_exit_status_2(tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:
        evaluation.cli.main(["--dataset", "synthetic:0", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1
    assert "no chosen frame of synthetic:0 has an object to match" in err
    assert not (tmp_path / "out").exists() and leftovers(tmp_path / "out") == []


def test_a_binary_file_given_as_a_csv_is_named_in_one_line(tmp_path, capsys):
    binary = tmp_path / "boxes.csv"
    binary.write_bytes(bytes(range(256)) * 40 + b"\n" * 30)
    with pytest.raises(SystemExit) as stop:
        evaluation.cli.main(["--dataset", str(binary), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and err.count("\n") == 1
    assert f"{binary}: binary content, not a CSV file; expected UTF-8 text" in err


def test_stopping_the_pool_ends_its_manager_thread_before_the_process_may_exit():
    """The manager thread holds the pool's queues: were it still running when a stopped run exits,
    it could be cut between unlinking a semaphore and telling the resource tracker ("leaked semaphore")."""
    threads, children = set(threading.enumerate()), set(multiprocessing.active_children())
    pool = ProcessPoolExecutor(max_workers=2, mp_context=multiprocessing.get_context("spawn"))
    for _ in range(3):
        pool.submit(time.sleep, 60)
    processes = [p for p in multiprocessing.active_children() if p not in children]
    wait_for(lambda: all(p.pid for p in processes) and len(processes) == 2, 60, "the pool's two workers")
    started = [thread for thread in threading.enumerate() if thread not in threads]
    assert started, "the pool's manager thread"
    stop_pool(pool, processes)
    assert not any(thread.is_alive() for thread in started) and not any(p.is_alive() for p in processes)
