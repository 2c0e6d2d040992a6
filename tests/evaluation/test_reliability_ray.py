"""``--ray`` that cannot hang (issue 27, rows 1 and 2): an address where something that is not Ray
listens is refused in one line, the port range is checked, and a stop signal during a local Ray
instance's start-up ends the run with one line and no Ray process left behind."""
from __future__ import annotations

import contextlib
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from evaluation import executors
from evaluation.cli import main
from evaluation.executors import ExecutorError, check_reachable
from evaluation.stop import Stopped
from support.processes import alive, descendants, wait_for

REPO = Path(__file__).resolve().parents[2]
QUICK = ["--dataset", "synthetic:20", "--frames", "0:2", "--methods", "icp", "--workers", "1"]


@contextmanager
def listener(reply: bytes | None) -> Iterator[tuple[str, threading.Event]]:
    """A TCP server on loopback that is not Ray: it accepts, then sends ``reply`` (None: nothing,
    the connection held open); yields its address and an event set once it has accepted."""
    server = socket.create_server(("127.0.0.1", 0))
    accepted = threading.Event()
    held: list[socket.socket] = []

    def serve() -> None:
        while True:
            try:
                connection, _ = server.accept()
            except OSError:
                return
            held.append(connection)
            if reply is not None:
                connection.sendall(reply)
            accepted.set()

    threading.Thread(target=serve, daemon=True).start()
    try:
        yield f"127.0.0.1:{server.getsockname()[1]}", accepted
    finally:
        server.close()
        for connection in held:
            connection.close()


def test_a_silent_listener_is_not_taken_for_a_ray_cluster() -> None:
    with listener(None) as (address, _):
        started = time.monotonic()
        with pytest.raises(ExecutorError) as raised:
            check_reachable(address, timeout=2.0)
    assert time.monotonic() - started < 10
    assert str(raised.value) == (f"--ray {address}: something listens there but does not answer as a Ray cluster "
                                 "(no gRPC reply within 2 s); give the head's GCS address (6379 by default)")


def test_a_web_server_is_not_taken_for_a_ray_cluster() -> None:
    with listener(b"HTTP/1.1 400 Bad Request\r\n\r\n") as (address, _):
        with pytest.raises(ExecutorError) as raised:
            check_reachable(address, timeout=5.0)
    assert str(raised.value) == (f"--ray {address}: something listens there but it is not a Ray cluster (its reply "
                                 "b'HTTP/1.1 ' is not gRPC); give the head's GCS address (6379 by default)")


@pytest.mark.parametrize("port", ["99999", "0", "65536"])
def test_a_port_out_of_range_is_one_line_before_anything_is_loaded(port, capsys, tmp_path) -> None:
    with pytest.raises(SystemExit) as stop:
        main([*QUICK, "--ray", f"127.0.0.1:{port}", "--out", str(tmp_path / "out")])
    assert stop.value.code == 2
    assert capsys.readouterr().err == (f"evaluate.py: error: --ray 127.0.0.1:{port}: the port must be between 1 "
                                       f"and 65535, got {int(port)}\n")


def test_evaluate_py_refuses_a_listener_that_is_not_ray_within_15_s(tmp_path) -> None:
    with listener(None) as (address, _):
        started = time.monotonic()
        done = subprocess.run([sys.executable, "evaluate.py", *QUICK, "--ray", address, "--out", str(tmp_path / "o")],
                              cwd=REPO, capture_output=True, text=True, timeout=120)
        took = time.monotonic() - started
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        f"evaluate.py: error: --ray {address}: something listens there but does not answer as a Ray cluster "
        "(no gRPC reply within 10 s); give the head's GCS address (6379 by default)"]
    assert took < 25, f"{took:.1f} s (10 s of waiting for the reply, the rest Python's start on a busy machine)"


def test_sigterm_while_waiting_for_the_listener_stops_without_waiting_for_it(tmp_path) -> None:
    with listener(None) as (address, accepted):
        process = subprocess.Popen([sys.executable, "evaluate.py", *QUICK, "--ray", address,
                                    "--out", str(tmp_path / "o")], cwd=REPO, stderr=subprocess.PIPE, text=True)
        assert accepted.wait(120), "evaluate.py never connected"
        started = time.monotonic()
        process.send_signal(signal.SIGTERM)
        stderr = process.communicate(timeout=60)[1]
        took = time.monotonic() - started
    assert process.returncode == 143 and stderr.strip() == "evaluate.py: stopped by SIGTERM; nothing written"
    assert took < 8.0, f"stopped after {took:.1f} s: it waited for the listener (about 11 s) before acting"


def ray_processes(marker: str) -> list[int]:
    """Live processes whose command line names ``marker`` (the run's own Ray temporary folder)."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if marker.encode() in (entry / "cmdline").read_bytes() and alive(int(entry.name)):
                    found.append(int(entry.name))
            except OSError:
                continue
    return found


@pytest.mark.ray
@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT])
def test_a_stop_signal_during_ray_local_start_up_leaves_no_process(signum: int) -> None:
    temporary = tempfile.mkdtemp(prefix="r27", dir="/tmp")  # Ray's folder: a short path for its sockets
    try:
        out = Path(temporary) / "out"
        process = subprocess.Popen([sys.executable, "evaluate.py", *QUICK, "--ray", "local", "--out", str(out)],
                                   cwd=REPO, stderr=subprocess.PIPE, text=True,
                                   env={**os.environ, "RAY_TMPDIR": temporary})
        wait_for(lambda: any(b"raylet" in Path(f"/proc/{pid}/cmdline").read_bytes()
                             for pid in descendants(process.pid) if alive(pid)) or process.poll() is not None,
                 180, "Ray's raylet to start")
        started = time.monotonic()
        process.send_signal(signum)
        stderr = process.communicate(timeout=120)[1]
        took = time.monotonic() - started
        assert process.returncode == 128 + signum, stderr
        assert stderr.strip() == f"evaluate.py: stopped by {signal.Signals(signum).name}; nothing written"
        assert took < 10.0, f"stopped after {took:.1f} s: it waited for Ray's start-up to finish"
        wait_for(lambda: not ray_processes(temporary), 10, "Ray's processes to be gone")
    finally:
        shutil.rmtree(temporary, ignore_errors=True)


def running_a_task(pid: int) -> bool:
    """Whether a Ray worker descended from ``pid`` runs a task (Ray names such a worker ``ray::<task>``)."""
    names = []
    for child in descendants(pid):
        with contextlib.suppress(OSError):
            names.append(Path(f"/proc/{child}/cmdline").read_bytes())
    return any(name.startswith(b"ray::") and not name.startswith(b"ray::IDLE") for name in names)


@pytest.mark.ray
@pytest.mark.parametrize("signum, group", [(signal.SIGTERM, False), (signal.SIGINT, True)] * 2,
                         ids=["SIGTERM", "Ctrl-C", "SIGTERM again", "Ctrl-C again"])
def test_a_stop_signal_while_ray_runs_tasks_is_one_line_and_leaves_no_process(signum: int, group: bool) -> None:
    """Issue 50, item 7 (was: status 1 and Ray's C++ crash report in 5 of 16 tries, its dashboard
    and runtime-env agents left running)."""
    temporary = tempfile.mkdtemp(prefix="r50", dir="/tmp")
    try:
        process = subprocess.Popen([sys.executable, "evaluate.py", "--dataset", "synthetic:100", "--workers", "2",
                                    "--ray", "local", "--out", str(Path(temporary) / "out")], cwd=REPO,
                                   stderr=subprocess.PIPE, text=True, start_new_session=True,
                                   env={**os.environ, "RAY_TMPDIR": temporary})
        wait_for(lambda: running_a_task(process.pid) or process.poll() is not None, 240, "a Ray task to run")
        assert process.poll() is None, process.stderr.read()
        os.killpg(process.pid, signum) if group else process.send_signal(signum)
        stderr = process.communicate(timeout=120)[1]
        assert process.returncode == 128 + signum, stderr
        assert stderr == f"evaluate.py: stopped by {signal.Signals(signum).name}; nothing written\n"
        wait_for(lambda: not ray_processes(temporary), 10, "Ray's processes to be gone")
    finally:
        for pid in ray_processes(temporary):
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
        shutil.rmtree(temporary, ignore_errors=True)


class FakeRay:
    """Ray's calls that ``evaluation.executors`` makes, recorded; ``wait`` is where a stop lands."""

    def __init__(self) -> None:
        self.calls: list[str] = []
        self.initialized = False

    def init(self, **_) -> None:
        self.calls.append("init")
        self.initialized = True

    def is_initialized(self) -> bool:
        return self.initialized

    def shutdown(self) -> None:
        self.calls.append("shutdown")

    def remote(self, **_):
        return lambda fn: type("Remote", (), {"remote": staticmethod(lambda *args: object())})

    def put(self, value):
        return value

    def wait(self, pending, num_returns, timeout=None):
        """As Ray answers our handler's ``Stopped`` raised where its compiled code checks for signals."""
        try:
            raise Stopped(signal.SIGTERM)
        except Stopped as stop:
            raise SystemError("<cyfunction CoreWorker.wait> returned a result with an exception set") from stop

    def cancel(self, ref, force=False) -> None:
        self.calls.append("cancel")


def test_a_stop_makes_no_ray_call_the_commands_end_kills_the_instance(monkeypatch) -> None:
    """Issue 50, item 7: a stop inside ``ray.wait`` is raised as the stop (Ray turns it into a
    ``SystemError``: status 1 and a traceback), and neither a forced cancel (whose task may then
    complete: Ray's "Tried to complete task that was not pending" crash) nor ``ray.shutdown``
    (racing the stop's deadline, and ending the raylet before its agents) is called; ``exit_now``
    kills the instance."""
    fake = FakeRay()
    monkeypatch.setitem(sys.modules, "ray", fake)
    with pytest.raises(Stopped), executors.ray_session("local", workers=2):
        executors.run_tasks(pow, [(2, 3), (2, 4)], ray="local")
    assert fake.calls == ["init"]
    fake.initialized = False
    with executors.ray_session("local", workers=2):
        pass
    assert fake.calls == ["init", "init", "shutdown"]


@pytest.mark.ray
def test_ray_leaves_pythons_handler_of_sigterm_in_place(tmp_path) -> None:
    """Ray's core worker installed a C++ handler of SIGTERM in the middle of ``ray.init``: a stop
    then printed Ray's crash report ("*** SIGTERM received ...") and could end the process with
    status -15. Here the signal comes right after ``ray.init``, before anything puts a handler back."""
    script = ("import os, signal, time\nfrom evaluation.executors import import_ray\nray = import_ray()\n"
              "ray.init(num_cpus=1, include_dashboard=False, log_to_driver=False, logging_level='ERROR')\n"
              "os.kill(os.getpid(), signal.SIGTERM)\ntime.sleep(30)\n")
    temporary = tempfile.mkdtemp(prefix="r50", dir="/tmp")
    try:
        done = subprocess.run([sys.executable, "-c", script], cwd=REPO, capture_output=True, text=True, timeout=240,
                              env={**os.environ, "RAY_TMPDIR": temporary, "PYTHONPATH": str(REPO)})
        assert "SIGTERM received" not in done.stderr, done.stderr
        assert done.returncode == signal.SIGTERM, done.stderr
    finally:
        for pid in ray_processes(temporary):
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
        shutil.rmtree(temporary, ignore_errors=True)
