"""The two commands' entry points (``cbm-evaluate``, ``cbm-explorer``; ``evaluate.py`` and
``serve.py`` call them too): a stop signal from the first line on ends the command with one line,
and every warning is one line (``one_line_warnings``).

Importing numpy, polars, viser and the project takes about a second; a Ctrl-C or SIGTERM meanwhile
would print a ``KeyboardInterrupt`` traceback or end the process without a word. This module
imports nothing heavy, so its handler is in place first; the commands replace it with their own
(``evaluation.stop``) once they are ready to clean up.
"""
from __future__ import annotations

import os
import signal
import sys
import warnings
from types import FrameType


def stop_while_importing(prog: str) -> None:
    """SIGINT and SIGTERM end the process at once with ``PROG: stopped by SIGNAL`` and status 128 +
    the signal (nothing has started yet, so there is nothing to clean up)."""
    def handle(signum: int, frame: FrameType | None) -> None:
        os.write(2, f"{prog}: stopped by {signal.Signals(signum).name}\n".encode())
        os._exit(128 + signum)

    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, handle)


def one_line_warnings(prog: str) -> None:
    """Every warning (a loader's skipped files, a calibration fallback) on the console as one line,
    ``PROG: warning: message``, in place of Python's category, file and source line."""
    def formatted(message: Warning | str, category: type[Warning], filename: str, lineno: int,
                  line: str | None = None) -> str:
        return f"{prog}: warning: {' '.join(str(message).split())}\n"

    warnings.formatwarning = formatted


def evaluate(argv: list[str] | None = None) -> int:
    """``cbm-evaluate``: ``evaluation.cli.main`` once imported; the command's handler only when run as
    the command (``argv`` None), never inside a caller's process."""
    if argv is None:
        stop_while_importing("evaluate.py")
        one_line_warnings("evaluate.py")
    from evaluation.cli import main
    return main(argv)


def serve(argv: list[str] | None = None) -> int:
    """``cbm-explorer``: ``app.cli.main`` once imported (the handler as for :func:`evaluate`)."""
    if argv is None:
        stop_while_importing(os.path.basename(sys.argv[0]))
        one_line_warnings(os.path.basename(sys.argv[0]))
    from app.cli import main
    return main(argv)
