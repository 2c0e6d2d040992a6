"""Running a command that obeys file permissions although the tests run as root.

Root reads and writes any file whatever its mode (the capabilities CAP_DAC_OVERRIDE and
CAP_DAC_READ_SEARCH), so an "unreadable folder" test would pass for the wrong reason. A child
started with :func:`obeying_permissions` as its ``preexec_fn`` has both capabilities removed from
its bounding set before ``exec``: the program it runs keeps uid 0 (it can still import from
root's folders) but gets "Permission denied" like any user.
"""
from __future__ import annotations

import ctypes
import os
import subprocess
import sys

import pytest

PR_CAPBSET_DROP = 24
CAP_DAC_OVERRIDE = 1
CAP_DAC_READ_SEARCH = 2


def drop_permission_override() -> None:
    """In the child before ``exec``: give up overriding file permissions (no-op when not root)."""
    if os.geteuid() != 0:
        return
    libc = ctypes.CDLL(None, use_errno=True)
    for capability in (CAP_DAC_OVERRIDE, CAP_DAC_READ_SEARCH):
        if libc.prctl(PR_CAPBSET_DROP, capability, 0, 0, 0) != 0:
            raise OSError(ctypes.get_errno(), f"prctl(PR_CAPBSET_DROP, {capability})")


def obeying_permissions():
    """``drop_permission_override`` after checking that it works here (a child with it cannot read a
    mode-000 file); the test is skipped, with the reason, where it does not."""
    probe = ("import os, tempfile\nf = tempfile.mkstemp()[1]\nos.chmod(f, 0)\ntry:\n    open(f).close()\n"
             "except PermissionError:\n    raise SystemExit(0)\nfinally:\n    os.unlink(f)\nraise SystemExit(1)")
    try:
        done = subprocess.run([sys.executable, "-c", probe], preexec_fn=drop_permission_override,
                              capture_output=True, timeout=120)
    except subprocess.SubprocessError as error:
        pytest.skip(f"cannot drop the permission override here ({error})")
    if done.returncode != 0:
        pytest.skip("cannot make a child obey file permissions here (no CAP_SETPCAP to drop CAP_DAC_OVERRIDE)")
    return drop_permission_override
