"""The ``cbm-explorer`` command (also ``python serve.py``): the live CBM calibration explorer in the browser.

    cbm-explorer [--dataset PATH_OR_NAME] [--data FOLDER ...] [--preset NAME] [--host 127.0.0.1] [--port 8080]
                 [--allow-host NAME]
    cbm-explorer --list-presets
"""
from __future__ import annotations

import argparse
import contextlib
import os
import signal
import sys
import threading
import time

import loaders
from evaluation.stop import FORCE_AFTER_S, Watchdog, force_exit, kill_descendants

from .panels.registry import tabs_help
from .scene.words import plural
from .server import AddressError, ExplorerServer, check_free, host_port, is_loopback
from .session import kernels
from .session.datasets import Catalogue, DataError, data_roots, start_dataset
from .session.explorer import Explorer
from .session.offers import offers_of
from .session.presets import PresetError, discover
from .session.settings import Settings
from .session.start import FEWEST_SHARED, first_usable


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:
        raise SystemExit(_fail(message))


def _fail(message: str) -> int:
    print(f"{os.path.basename(sys.argv[0])}: error: {message}", file=sys.stderr)
    return 2


def parse(argv: list[str]) -> argparse.Namespace:
    """The command line's options; a wrong one exits with one line on stderr and status 2."""
    parser = _Parser(description="CBM Explorer: see and tune CBM's pose calibration live in the browser.",
                     epilog=f"The tabs of the control panel:\n{tabs_help()}",
                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--dataset", default="argoverse2",
                        help="dataset folder or file, or a name: argoverse2 (shipped), synthetic[:count[:seed=S]]")
    parser.add_argument("--data", action="extend", nargs="+", default=[], metavar="FOLDER",
                        help="folders whose datasets the page offers besides the shipped scene, found at start "
                             "(repeatable); nothing outside them is listed or read")
    parser.add_argument("--preset", default="default",
                        help="preset to start from (a shipped one or one saved in your presets folder)")
    parser.add_argument("--detections", default=None, metavar="STAGE1_BOXES_JSON",
                        help="CoAlign / HEAL stage1_boxes.json: a detector's boxes replace the simulated detections")
    parser.add_argument("--host", default="127.0.0.1", help="address to listen on (default: loopback only)")
    parser.add_argument("--port", type=int, default=8080, help="port (0: any free port)")
    parser.add_argument("--allow-host", action="append", default=[], metavar="NAME",
                        help="a host name the browser may use to reach the app besides localhost, IP addresses "
                             "and --host (repeatable; to serve on a LAN by name)")
    parser.add_argument("--list-presets", action="store_true",
                        help="list the shipped presets and the ones in your presets folder, then exit")
    args = parser.parse_args(argv)
    if not 0 <= args.port <= 65535:
        parser.error(f"--port must be between 0 and 65535, got {args.port}")
    return args


SAMPLED_FRAMES = 25
"""Frames, evenly spread, that the start-up check tries for a usable ego and CAV."""


def kernels_ready_line(kernels) -> str:
    """The console line once CBM's kernels are loaded: until then small frames ran interpreted."""
    spent = (kernels.compile_seconds or 0.0) + (kernels.load_seconds or 0.0)
    how = f"compiled in {spent:.1f} s, cached from now on" if kernels.note() else "loaded from the cache"
    return f"CBM's kernels ready ({how})."


def _warn(message: str) -> None:
    print(f"{os.path.basename(sys.argv[0])}: warning: {message}", file=sys.stderr, flush=True)


def sampled_frames(count: int, samples: int = SAMPLED_FRAMES) -> list[int]:
    """Up to ``samples`` frame indices spread evenly over ``count`` frames, the first and last included."""
    if count <= samples:
        return list(range(count))
    return sorted({round(k * (count - 1) / (samples - 1)) for k in range(samples)})


def usable_frame(explorer: Explorer, settings: Settings) -> int | None:
    """The first sampled frame that makes a trial (an ego and a CAV with objects) under ``settings``, or None."""
    return first_usable(explorer, settings, sampled_frames(len(explorer)))


def _stop_while_starting() -> Watchdog:
    """Until the server runs, SIGTERM and SIGINT end the command at once (the kernels' compiling
    subprocesses killed, one line, status 128 + the signal); the watchdog acts for them when the main
    thread is stuck in a long call (reading a large dataset, or a server that never gets ready).
    Once the server is built the watchdog stands down and a signal stops the server cleanly."""
    def line(name: str) -> str:
        return f"{os.path.basename(sys.argv[0])}: stopped by {name} while starting"

    for number in (signal.SIGTERM, signal.SIGINT):
        signal.signal(number, lambda signum, _: force_exit(line(signal.Signals(signum).name), signum))
    return Watchdog(line)


def _stop_on_signals() -> threading.Event:
    """An event set by SIGTERM or SIGINT (Ctrl-C), so that the server stops cleanly on either."""
    stopping = threading.Event()
    for number in (signal.SIGTERM, signal.SIGINT):
        signal.signal(number, lambda *_: stopping.set())
    return stopping


def list_presets() -> int:
    """Print every preset a ``--preset`` may name, one line each: name, where it comes from, description."""
    presets, problems = discover()
    for problem in problems:
        _warn(f"preset skipped: {problem}")
    width = max((len(name) for name in presets), default=0)
    for name, preset in presets.items():
        origin = "shipped" if preset.shipped else "yours"
        print(f"{name:<{width}}  {origin:<7}  {preset.description}".rstrip())
    return 0


def main(argv: list[str] | None = None) -> int:
    """Serve the dataset until SIGTERM or Ctrl-C (then 0); 2 on bad input; 128 + the signal when
    one comes before the server runs (the command only: ``argv`` None)."""
    args = parse(sys.argv[1:] if argv is None else argv)
    if args.list_presets:
        return list_presets()
    starting = _stop_while_starting() if argv is None else None
    try:
        check_free(args.host, args.port)
        local = is_loopback(args.host)
    except AddressError as error:
        return _fail(f"cannot listen on {host_port(args.host, args.port)}: {error}")
    kernels.prepare()
    try:
        roots = data_roots(args.data)
        sequence = loaders.open(args.dataset, detections=args.detections)
    except (DataError, loaders.LoaderError) as error:
        return _fail(str(error))
    if len(sequence) == 0:
        return _fail(f"{args.dataset}: the dataset has no frames")
    presets, problems = discover()
    for problem in problems:
        _warn(f"preset skipped: {problem}")
    if args.preset not in presets:
        return _fail(f"--preset {args.preset!r} not found; available: {', '.join(presets)}")
    try:
        settings = presets[args.preset].apply(Settings())
    except (KeyError, TypeError, ValueError) as error:
        return _fail(str(PresetError(f"{args.preset}: {error}")))
    refused = offers_of(sequence).refusal(settings)
    if refused:
        return _fail(f"--preset {args.preset}: {refused}")
    explorer = Explorer(sequence)
    if usable_frame(explorer, settings) is None:
        _warn(f"no frame has {FEWEST_SHARED} objects seen by both an ego and a CAV under the "
              f"{settings.scenario.protocol} protocol among {len(sampled_frames(len(sequence)))} frames tried: CBM "
              f"cannot run; the page says what is missing")
    catalogue = Catalogue(start_dataset(args.dataset), explorer, roots)
    stopping = _stop_on_signals()
    try:
        server = ExplorerServer(explorer, settings, host=args.host, port=args.port, allowed_hosts=args.allow_host,
                                catalogue=catalogue)
    except OSError as error:
        return _fail(f"cannot listen on {host_port(args.host, args.port)}: {error}")
    if starting:
        starting.disarm()
    if not local:
        _warn(f"listening on {args.host}, beyond this machine: the app has no authentication, anyone who can "
              f"reach this address can use it")
    offered = f"; {len(catalogue.names)} datasets offered" if len(catalogue.names) > 1 else ""
    print(f"CBM Explorer on {sequence.name} ({plural(len(sequence), 'frame')}{offered}): open {server.url}",
          flush=True)
    server.kernels.when_ready(lambda: print(kernels_ready_line(server.kernels), flush=True))
    while not stopping.wait(0.1):
        pass
    for number in (signal.SIGTERM, signal.SIGINT):
        signal.signal(number, lambda signum, _: force_exit(f"stopped by {signal.Signals(signum).name}", signum))
    _end_soon()
    server.stop()
    server.kernels.stop()
    return 0


def _end_soon(grace: float = FORCE_AFTER_S) -> None:
    """End the process ``grace`` seconds from now, status 0, if it still runs: a tab's computation
    inside a compiled kernel cannot be interrupted, and the interpreter would wait for it at exit
    (issue 40: "Server stopped", then minutes at 200 % CPU, deaf to a second signal)."""
    def end() -> None:
        time.sleep(grace)
        kill_descendants()
        with contextlib.suppress(OSError, ValueError):
            sys.stdout.flush()
            sys.stderr.flush()
        os._exit(0)

    threading.Thread(target=end, name="stop-deadline", daemon=True).start()
