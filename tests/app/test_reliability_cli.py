"""The ``cbm-explorer`` command starts and stops cleanly (issue 16, parts 1 and 5): host and port
checked up front, a warning beyond loopback and for a dataset CBM cannot run on, SIGTERM and
SIGINT stop it within 2 s with status 0 and no traceback."""
from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from app.server import AddressError, check_free, resolve
from support.processes import line_with

REPO = Path(__file__).resolve().parents[2]


def _command(*args: str) -> list[str]:
    return [sys.executable, "serve.py", *args]


def _env(presets: Path) -> dict[str, str]:
    return {**os.environ, "CBM_EXPLORER_PRESETS": str(presets)}


def _run(*args: str, presets: Path, timeout: float = 60) -> subprocess.CompletedProcess:
    return subprocess.run(_command(*args), cwd=REPO, capture_output=True, text=True, timeout=timeout,
                          env=_env(presets))


@contextmanager
def serving(*args: str, presets: Path) -> Iterator[tuple[subprocess.Popen, str]]:
    """A running server and its URL (the line it prints once it listens)."""
    process = subprocess.Popen(_command(*args), cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True, env=_env(presets))
    try:
        for line in process.stdout:
            if "open http" in line:
                yield process, line.rsplit(" ", 1)[-1].strip()
                return
        raise AssertionError(f"the server did not start: {process.stderr.read()}")
    finally:
        if process.poll() is None:
            process.kill()
            process.wait(timeout=10)


@pytest.mark.parametrize("host", ["256.1.1.1", "no-such-host.invalid"])
def test_a_host_that_does_not_resolve_is_one_line_at_once(host: str, tmp_path: Path) -> None:
    started = time.monotonic()
    done = _run("--host", host, presets=tmp_path)
    assert time.monotonic() - started < 30
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and "does not resolve" in lines[0]
    assert "Traceback" not in done.stderr


def test_a_taken_port_is_an_error_not_a_silent_move(tmp_path: Path) -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        done = _run("--port", str(port), presets=tmp_path)
        with pytest.raises(AddressError, match="taken"):
            check_free("127.0.0.1", port)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and f"port {port}" in lines[0] and "taken" in lines[0]


def test_resolve_gives_up_after_its_timeout(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(socket, "getaddrinfo", lambda *a, **k: time.sleep(60))
    started = time.monotonic()
    with pytest.raises(AddressError, match="did not resolve within"):
        resolve("slow.example", 80, timeout=0.3)
    assert time.monotonic() - started < 30, "resolve waited for the resolver instead of its timeout"


@pytest.mark.parametrize("number", [signal.SIGTERM, signal.SIGINT])
def test_sigterm_and_sigint_stop_the_server_cleanly(number: int, tmp_path: Path) -> None:
    with serving("--port", "0", presets=tmp_path) as (process, url):
        assert url.startswith("http://127.0.0.1:")
        urllib.request.urlopen(url, timeout=30).close()
        line_with(process, "kernels ready", 600.0)
        process.send_signal(number)
        process.wait(timeout=60)
        assert process.returncode == 0 and "Traceback" not in process.stderr.read()


def test_binding_beyond_loopback_warns_that_there_is_no_authentication(tmp_path: Path) -> None:
    with serving("--host", "0.0.0.0", "--port", "0", presets=tmp_path) as (process, _):
        process.send_signal(signal.SIGTERM)
        process.wait(timeout=10)
        assert "no authentication" in process.stderr.read()


@pytest.mark.parametrize("dataset", ["synthetic:0", "synthetic:1"])
def test_a_dataset_without_a_usable_pair_warns_at_start(dataset: str, tmp_path: Path) -> None:
    with serving("--dataset", dataset, "--port", "0", presets=tmp_path) as (process, _):
        process.send_signal(signal.SIGTERM)
        process.wait(timeout=10)
        assert "no frame has 3 objects seen by both an ego and a CAV" in process.stderr.read()


def test_a_usable_dataset_starts_without_that_warning(tmp_path: Path) -> None:
    with serving("--dataset", "synthetic:20", "--port", "0", presets=tmp_path) as (process, _):
        process.send_signal(signal.SIGTERM)
        process.wait(timeout=10)
        assert "seen by both" not in process.stderr.read()


def test_viser_moving_to_another_port_is_caught_after_start(monkeypatch: pytest.MonkeyPatch) -> None:
    import loaders
    from app import server as module
    from app.session.explorer import Explorer
    from app.session.settings import Settings

    monkeypatch.setattr(module, "check_free", lambda host, port: None)
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        with pytest.raises(AddressError, match=f"port {port} was taken"):
            module.ExplorerServer(Explorer(loaders.open("synthetic:4")), Settings(), port=port)
