"""CBM without the compiler: the same kernels run as the plain Python functions numba compiles.

Every numba kernel of CBM (context, steps 1-4's local matching and voting sets, step 5's consensus,
step 6's selection) is a Python function under ``@numba.njit``; numba keeps the original as the
dispatcher's ``py_func``. Inside ``interpreted()`` each module of ``cbm`` names the original instead
of the dispatcher, so ``match`` runs every step in the interpreter, on the same arrays and in the
same order: the same pairs and transform, compiled or not, at no compile cost. It takes tenths of
a second on a frame of 30-50 objects per agent (``SMALL``), against the seconds numba takes to
compile the kernels on a fresh install; a server answers its first frames this way while the
kernels compile in the background (``app.session.kernels``).

Only one ``interpreted()`` block runs at a time (``LOCK``); whoever loads or compiles the kernels
in this process holds ``LOCK`` meanwhile, because numba would then read the swapped names.
"""
from __future__ import annotations

import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager

from numba.core.registry import CPUDispatcher

SMALL = 150
"""Objects per agent up to which the interpreted path is quick enough for a first frame (<1 s)."""

LOCK = threading.RLock()
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


@contextmanager
def interpreted() -> Iterator[None]:
    """Within the block, ``cbm.match`` runs its kernels' plain Python functions (nothing compiles)."""
    with LOCK:
        swapped = kernels()
        try:
            for module, attribute, dispatcher in swapped:
                setattr(module, attribute, dispatcher.py_func)
            yield
        finally:
            for module, attribute, dispatcher in swapped:
                setattr(module, attribute, dispatcher)
