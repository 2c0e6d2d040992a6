"""``serve.py`` inputs that used to hang it or print a traceback (issue 27, rows 11 and 12): a FIFO
among the preset files, a presets folder it may not list, an address it cannot bind."""
from __future__ import annotations

import os
import queue
import signal
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from app import server as module
from tests.support.privileges import obeying_permissions

REPO = Path(__file__).resolve().parents[2]


def serve(*args: str, presets: Path, preexec=None) -> subprocess.Popen:
    """``serve.py`` started with its user presets in ``presets``."""
    return subprocess.Popen([sys.executable, "serve.py", *args], cwd=REPO, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, preexec_fn=preexec,
                            env={**os.environ, "CBM_EXPLORER_PRESETS": str(presets)})


def finished(process: subprocess.Popen, limit: float = 300.0) -> tuple[str, str]:
    """Stdout and stderr of ``process`` once it exits; killed, and the test failed, if it is still
    running after ``limit`` seconds (the hang these tests guard against)."""
    try:
        return process.communicate(timeout=limit)
    except subprocess.TimeoutExpired:
        process.kill()
        err = process.communicate()[1]
        raise AssertionError(f"still running after {limit:.0f} s (killed): {err[-2000:]}") from None


def url_line(process: subprocess.Popen, limit: float = 300.0) -> str:
    """The line a server prints once it listens ("" when it exits first or ``limit`` seconds pass)."""
    found: queue.Queue[str] = queue.Queue()
    threading.Thread(target=lambda: found.put(next((line for line in process.stdout if "open http" in line), "")),
                     daemon=True).start()
    try:
        return found.get(timeout=limit)
    except queue.Empty:
        return ""


def ended(process: subprocess.Popen) -> str:
    """Stderr of ``process`` after killing it if it still runs."""
    process.kill()
    return process.communicate()[1]


def presets_with_a_fifo(tmp_path: Path) -> Path:
    folder = tmp_path / "presets"
    folder.mkdir()
    os.mkfifo(folder / "blocking.toml")
    (folder / "mine.toml").write_text('description = "mine"\n[cbm]\nsigma2 = 2\n')
    return folder


def test_a_fifo_among_the_presets_is_skipped_with_a_warning_not_opened(tmp_path: Path) -> None:
    folder = presets_with_a_fifo(tmp_path)
    listing = serve("--list-presets", presets=folder)
    out, err = finished(listing)
    assert listing.returncode == 0 and "mine" in out and "Traceback" not in err
    assert "warning: preset skipped: blocking.toml: a FIFO (named pipe), not a regular file; not read" in err
    server = serve("--dataset", "synthetic:5", "--port", "0", "--preset", "mine", presets=folder)
    try:
        assert url_line(server), ended(server)
        server.send_signal(signal.SIGTERM)
        _, err = finished(server)
        assert server.returncode == 0 and "blocking.toml: a FIFO (named pipe)" in err, err
    finally:
        ended(server)


def test_a_presets_folder_that_cannot_be_listed_is_a_warning(tmp_path: Path) -> None:
    preexec = obeying_permissions()
    folder = tmp_path / "presets"
    folder.mkdir()
    (folder / "mine.toml").write_text("[cbm]\nsigma2 = 2\n")
    folder.chmod(0)
    listing = serve("--list-presets", presets=folder, preexec=preexec)
    try:
        out, err = finished(listing)
    finally:
        folder.chmod(0o755)
    assert listing.returncode == 0 and "default" in out and "Traceback" not in err, err
    assert f"warning: preset skipped: {folder}: the presets folder cannot be listed (Permission denied)" in err


def test_an_address_that_cannot_be_bound_is_one_line_not_a_hang(tmp_path: Path) -> None:
    server = serve("--host", "::ffff:127.0.0.1", "--port", "0", "--dataset", "synthetic:5", presets=tmp_path)
    _, err = finished(server)
    lines = err.strip().splitlines()
    assert server.returncode == 2 and len(lines) == 1 and "Traceback" not in err, err
    assert lines[0] == ("serve.py: error: cannot listen on [::ffff:127.0.0.1]:0: the address ::ffff:127.0.0.1 "
                        "cannot be bound (Invalid argument); use --host 127.0.0.1 instead")


def test_viser_not_listening_in_time_is_an_error_not_a_hang(monkeypatch: pytest.MonkeyPatch) -> None:
    release = threading.Event()
    monkeypatch.setattr(module.viser, "ViserServer", lambda **_: release.wait())
    try:
        with pytest.raises(module.AddressError, match=r"did not start listening on \[::1\]:8080 within 0 s"):
            module.start_viser("::1", 8080, verbose=False, timeout=0.2)
    finally:
        release.set()


@pytest.mark.parametrize("host", ["::1", "::"])
def test_an_ipv6_host_is_printed_in_brackets(host: str, tmp_path: Path) -> None:
    server = serve("--host", host, "--port", "0", "--dataset", "synthetic:5", presets=tmp_path)
    try:
        line = url_line(server)
        assert line.rsplit(" ", 1)[-1].strip().startswith(f"http://[{host}]:"), (line, ended(server))
        server.send_signal(signal.SIGTERM)
        finished(server)
        assert server.returncode == 0
    finally:
        ended(server)
