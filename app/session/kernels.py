"""CBM's compiled kernels, made ready once per server process, off the request path.

numba compiles CBM's kernels on their first call, which takes seconds on a fresh install, and keeps
them in its on-disk cache. At server start ``prepare`` compiles them in two subprocesses at once
(``cbm.compile_side_by_side``; the compiler is mostly Python: in a thread it would hold
this process's interpreter lock and stall the server) while the dataset loads, then loads the
cached kernels into this process with one small match. Until then a recompute of a small frame
runs CBM interpreted (``running``: ``cbm.interpreted``, the same results without the compiler) and a
large one waits for ``ready``; the time spent compiling is reported on its own, never as CBM's time.
Then, the same way, the baselines' kernels (FreeAlign's search, and what V2X-Reg++ calls of CBM's);
a frame of a method that runs them (``BASELINES``) waits for them (``ready_for``): FreeAlign
interpreted takes seconds from 50 objects per agent on (2 s at 50, 7 s at 70, two minutes at 110).
"""
from __future__ import annotations

import atexit
import contextlib
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

from cbm import (
    COMPILE_LOCK,
    CompileFailed,
    compile_side_by_side,
    guard_compiles,
    interpreted,
    kernels_cached,
    load_kernels,
)

COMPILED_AFTER = 1.0
"""Seconds of compiling above which the kernels were compiled (a warm cache loads in a fraction of one)."""
COMPILING = ("CBM's kernels compiling (first start only): this result ran interpreted, no compile in its "
             "CBM time.")
"""What a result computed before the kernels were ready says beside its CBM time."""
TIMEOUT = 600.0
"""Seconds the compiling subprocesses may take before they are given up (this process then compiles)."""
BASELINES = ("freealign",)
"""The methods whose kernels come after CBM's (``cbm.warmup.compile_baselines``): FreeAlign's took
11-17 s to compile on its first use, in the middle of a tab's recompute. V2X-Reg++ has none of its
own (it runs on CBM's fitting kernels: 0.02 s on its first use once CBM's are loaded), so it never waits."""
BASELINE_PARTS = ("baselines",)


class Kernels:
    """CBM's kernels in this process: compiled (or found in the cache) by two subprocesses, then loaded."""

    def __init__(self) -> None:
        self.started = time.monotonic()
        guard_compiles()
        self.cached = kernels_cached()
        """The kernels were in numba's cache at start: loading them here takes a fraction of a second."""
        self.compile_seconds: float | None = None
        """Seconds the subprocesses took to fill the cache (None until they finished or if one failed)."""
        self.load_seconds: float | None = None
        """Seconds this process took to load them (to compile them too if the subprocess failed)."""
        self.baselines_cached = kernels_cached(baselines=True)
        self.baseline_seconds: float | None = None
        """Seconds the baselines' kernels took to compile (or load) once CBM's were ready (None until then)."""
        self._ready = threading.Event()
        self._baselines = threading.Event()
        self._processes: list[subprocess.Popen] = []
        self._waiting: list[Callable[[], None]] = []
        self._waiting_baselines: list[Callable[[], None]] = []
        atexit.register(self.stop)
        threading.Thread(target=self._prepare, name="cbm-kernels", daemon=True).start()

    @property
    def ready(self) -> bool:
        return self._ready.is_set()

    def ready_for(self, method: str) -> bool:
        """Whether the kernels ``method`` runs are loaded (CBM's, and the baselines' for ``BASELINES``)."""
        return self._event(method).is_set()

    def wait(self, timeout: float | None = None, method: str = "cbm") -> bool:
        """Block until the kernels ``method`` runs are loaded; False on timeout."""
        return self._event(method).wait(timeout)

    @contextmanager
    def running(self) -> Iterator[bool]:
        """CBM within the block runs compiled once the kernels are ready; until then interpreted
        (yields True), one block at a time, and never while this process loads them."""
        if not self.ready:
            with COMPILE_LOCK:
                if not self.ready:
                    with interpreted():
                        yield True
                    return
        yield False

    def when_ready(self, callback: Callable[[], None], method: str = "cbm") -> None:
        """Call ``callback`` once the kernels ``method`` runs are ready (at once if they are)."""
        with COMPILE_LOCK:
            if not self.ready_for(method):
                (self._waiting_baselines if method in BASELINES else self._waiting).append(callback)
                return
        callback()

    def _event(self, method: str) -> threading.Event:
        return self._baselines if method in BASELINES else self._ready

    def note(self) -> str:
        """What a first result says about the start-up compile ("" when nothing was compiled)."""
        compiled = self.load_seconds if self.compile_seconds is None else self.compile_seconds
        if not self.ready or (compiled or 0.0) < COMPILED_AFTER:
            return ""
        spent = (self.compile_seconds or 0.0) + (self.load_seconds or 0.0)
        return f"CBM's kernels compiled in {spent:.1f} s at start (cached from now on); not part of CBM's time."

    def stop(self) -> None:
        """End the compiling subprocesses, if they still run (at exit: they are no use to anyone then),
        and reap them: none is left listed as ``<defunct>``."""
        for process in self._processes:
            if process.poll() is None:
                process.kill()
        for process in self._processes:
            with contextlib.suppress(subprocess.TimeoutExpired):
                process.wait(timeout=1.0)

    def _compile_in_subprocess(self, parts: tuple[str, ...] | None = None) -> float | None:
        """Compile the kernels' ``parts`` (by default CBM's two halves) in processes of their own at
        once; the seconds they took, None when one failed."""
        try:
            if parts is None:
                return compile_side_by_side(self._processes, timeout=TIMEOUT)
            return compile_side_by_side(self._processes, timeout=TIMEOUT, parts=parts)
        except (OSError, subprocess.SubprocessError, ValueError, IndexError, CompileFailed):
            self.stop()
            return None

    def _prepare(self) -> None:
        """Fill the cache in subprocesses unless it holds the kernels, then load them here (or
        compile them here, when a subprocess failed); ready in any case, so that a broken kernel fails the recompute
        that calls it, with its own error, rather than making it wait forever."""
        self.compile_seconds = None if self.cached else self._compile_in_subprocess()
        with COMPILE_LOCK:
            try:
                started = time.perf_counter()
                load_kernels()
                self.load_seconds = time.perf_counter() - started
            finally:
                self._ready.set()
                waiting, self._waiting = self._waiting, []
        for callback in waiting:
            callback()
        self._prepare_baselines()

    def _prepare_baselines(self) -> None:
        """The baselines' kernels as CBM's: filled into the cache in a subprocess unless it holds
        them, then loaded here; ready in any case (a broken kernel fails the recompute that calls it)."""
        started = time.perf_counter()
        if not self.baselines_cached:
            self._compile_in_subprocess(BASELINE_PARTS)
        with COMPILE_LOCK:
            try:
                load_kernels(baselines=True)
                self.baseline_seconds = time.perf_counter() - started
            finally:
                self._baselines.set()
                waiting, self._waiting_baselines = self._waiting_baselines, []
        for callback in waiting:
            callback()


_shared: Kernels | None = None
_lock = threading.Lock()


def prepare() -> Kernels:
    """The process's ``Kernels``, started on the first call."""
    global _shared
    with _lock:
        if _shared is None:
            _shared = Kernels()
        return _shared
