"""The ``cbm-explorer`` command (also ``python serve.py``): the live CBM calibration explorer in the browser.

    cbm-explorer [--dataset PATH_OR_NAME] [--preset NAME] [--host 127.0.0.1] [--port 8080]
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import loaders

from .server import ExplorerServer
from .session import kernels
from .session.explorer import Explorer
from .session.presets import PresetError, discover
from .session.settings import Settings


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:
        raise SystemExit(_fail(message))


def _fail(message: str) -> int:
    print(f"{os.path.basename(sys.argv[0])}: error: {message}", file=sys.stderr)
    return 2


def parse(argv: list[str]) -> argparse.Namespace:
    """The command line's options; a wrong one exits with one line on stderr and status 2."""
    parser = _Parser(description="CBM Explorer: see and tune CBM's pose calibration live in the browser.")
    parser.add_argument("--dataset", default="argoverse2",
                        help="dataset folder or file, or a name: argoverse2 (shipped), synthetic[:count[:seed=S]]")
    parser.add_argument("--preset", default="default",
                        help="preset to start from (a shipped one or one saved in your presets folder)")
    parser.add_argument("--detections", default=None, metavar="STAGE1_BOXES_JSON",
                        help="CoAlign / HEAL stage1_boxes.json: a detector's boxes replace the simulated detections")
    parser.add_argument("--host", default="127.0.0.1", help="address to listen on (default: loopback only)")
    parser.add_argument("--port", type=int, default=8080, help="port (0: any free port)")
    args = parser.parse_args(argv)
    if not 0 <= args.port <= 65535:
        parser.error(f"--port must be between 0 and 65535, got {args.port}")
    return args


def main(argv: list[str] | None = None) -> int:
    """Serve the dataset until Ctrl-C; 2 on bad input."""
    args = parse(sys.argv[1:] if argv is None else argv)
    kernels.prepare()
    try:
        sequence = loaders.open(args.dataset, detections=args.detections)
    except loaders.LoaderError as error:
        return _fail(str(error))
    if len(sequence) == 0:
        return _fail(f"{args.dataset}: the dataset has no frames")
    presets, problems = discover()
    for problem in problems:
        print(f"{os.path.basename(sys.argv[0])}: warning: preset skipped: {problem}", file=sys.stderr)
    if args.preset not in presets:
        return _fail(f"--preset {args.preset!r} not found; available: {', '.join(presets)}")
    try:
        settings = presets[args.preset].apply(Settings())
    except (KeyError, TypeError, ValueError) as error:
        return _fail(str(PresetError(f"{args.preset}: {error}")))
    try:
        server = ExplorerServer(Explorer(sequence), settings, host=args.host, port=args.port)
    except OSError as error:
        return _fail(f"cannot listen on {args.host}:{args.port}: {error}")
    print(f"CBM Explorer on {sequence.name} ({len(sequence)} frames): open {server.url}", flush=True)
    try:
        while True:
            time.sleep(3600)
    except KeyboardInterrupt:
        server.stop()
    return 0
