"""CBM without the compiler: the same kernels run as the plain Python functions numba compiles.

Every numba kernel of CBM (context, steps 1-4's local matching and voting sets, step 5's consensus,
step 6's selection) is a Python function under ``@numba.njit``; numba keeps the original as the
dispatcher's ``py_func``. Inside ``interpreted()`` each module of ``cbm`` names the original instead
of the dispatcher, so ``match`` runs every step in the interpreter, on the same arrays and in the
same order: the same pairs and transform, compiled or not, at no compile cost. It takes tenths of
a second on a frame of 30-50 objects per agent (``INTERPRETED_UP_TO``), against the seconds numba takes to
compile the kernels on a fresh install; a server answers its first frames this way while the
kernels compile in the background (``app.session.kernels``).

Only one ``interpreted()`` block runs at a time (``COMPILE_LOCK``), and numba compiles (or loads from its
cache) none of the kernels while one runs: it would read the swapped names. ``guard_compiles``
makes every kernel's compile take ``COMPILE_LOCK`` (a compiled kernel never compiles again, so only the
first calls pay for it); ``interpreted()`` calls it, and so should whoever may compile in another
thread before the first block.
"""
from __future__ import annotations

import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from functools import wraps

from numba.core.registry import CPUDispatcher

INTERPRETED_UP_TO = 150
"""Objects per agent up to which the interpreted path is quick enough for a first frame (<1 s)."""

COMPILE_LOCK = threading.RLock()
"""Held by an ``interpreted()`` block, and by whoever loads or compiles the kernels meanwhile."""


def kernels() -> list[tuple[object, str, CPUDispatcher]]:
    """(module, name, dispatcher) of every numba kernel a loaded module of ``cbm`` names."""
    found = []
    for name, module in list(sys.modules.items()):
        if module is None or not (name == "cbm" or name.startswith("cbm.")):
            continue
        for attribute, value in list(vars(module).items()):
            if isinstance(value, CPUDispatcher):
                found.append((module, attribute, value))
    return found


def guard_compiles() -> None:
    """Every loaded kernel compiles (or loads from the cache) holding ``COMPILE_LOCK``, never during an
    ``interpreted()`` block of another thread."""
    for _, _, dispatcher in kernels():
        if not getattr(dispatcher.compile, "guarded", False):
            dispatcher.compile = _locked(dispatcher.compile)


def _locked(compile_: Callable) -> Callable:
    """``compile_`` holding ``COMPILE_LOCK``."""
    @wraps(compile_)
    def compile_holding_the_lock(*args, **kwargs):
        with COMPILE_LOCK:
            return compile_(*args, **kwargs)

    compile_holding_the_lock.guarded = True
    return compile_holding_the_lock


@contextmanager
def interpreted() -> Iterator[None]:
    """Within the block, ``cbm.match`` runs its kernels' plain Python functions (nothing compiles)."""
    guard_compiles()
    with COMPILE_LOCK:
        swapped = kernels()
        try:
            for module, attribute, dispatcher in swapped:
                setattr(module, attribute, dispatcher.py_func)
            yield
        finally:
            for module, attribute, dispatcher in swapped:
                setattr(module, attribute, dispatcher)
