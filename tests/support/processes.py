"""Watching a command's processes from a test, through /proc: its descendants, whether one is
alive, what it has loaded; and waiting for a condition with a generous limit."""
from __future__ import annotations

import threading
import time
from collections.abc import Callable
from pathlib import Path


def parent_of(pid: int) -> int | None:
    """The parent process id of ``pid`` (None when it is gone)."""
    try:
        return int(Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[1])
    except (OSError, IndexError, ValueError):
        return None


def descendants(pid: int) -> list[int]:
    """Every live process descended from ``pid``."""
    parents = {int(e.name): parent_of(int(e.name)) for e in Path("/proc").iterdir() if e.name.isdigit()}
    found, frontier = [], [pid]
    while frontier:
        parent = frontier.pop()
        children = [child for child, of in parents.items() if of == parent]
        found += children
        frontier += children
    return [child for child in found if alive(child)]


def alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie does not)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def has_loaded(pid: int, fragment: str) -> bool:
    """Whether ``pid`` has mapped a file whose path contains ``fragment`` (a library it imports)."""
    try:
        return fragment in Path(f"/proc/{pid}/maps").read_text()
    except OSError:
        return False


def wait_for(condition: Callable[[], bool], limit: float, what: str) -> None:
    """Poll ``condition`` until it holds; fail naming ``what`` after ``limit`` seconds (a generous bound)."""
    deadline = time.monotonic() + limit
    while not condition():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.02)


def line_with(process, words: str, timeout: float) -> str:
    """The next line of ``process``'s stdout (a text pipe) that holds ``words``; fails past ``timeout``
    seconds or when the process ends first. Read in a thread: lines may already wait in the pipe's
    buffer, where a ``select`` on the pipe would miss them and wait for output that never comes."""
    found: list[str] = []

    def read() -> None:
        for line in process.stdout:
            if words in line:
                found.append(line)
                return

    threading.Thread(target=read, name="line-reader", daemon=True).start()
    deadline = time.monotonic() + timeout
    while not found:
        assert time.monotonic() < deadline, f"no line with {words!r} within {timeout:.0f} s"
        assert process.poll() is None or found, f"the process ended (status {process.poll()}) with no {words!r}"
        time.sleep(0.1)
    return found[0]
