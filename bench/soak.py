"""Memory of a tab over many edits (issue 16, part 3): the server's resident memory (RSS) after a
warm-up and after ``--edits`` more edits, and whether a closed tab's session is freed.

No browser is needed for the memory: the app's server runs in this process on a free loopback port
and a plain websocket client stands in for the tab (it speaks viser's subprotocol and reads, then
drops, every message). The edits go through the tab's one entry point (``ClientSession.apply``) and
alternate the frame and CBM's sigma2; after each the context inspector shows the winning anchor,
and the walkthrough is active throughout, moving through its nine steps. Each edit is
waited for (computed and delivered) before the next.

    python bench/soak.py [--datasets argoverse2 synthetic:300] [--edits 300] [--warmup 30]
    python bench/soak.py --rounds 4 [--edits 300] [--steps 100] [--datasets synthetic:300]

``--rounds R`` (issue 40, item 4): R tabs in turn, each opened, edited ``--edits`` times on sigma2
and stepped ``--steps`` frames, then closed; the server's RSS after each close. What a closed tab
leaves behind grows it round after round.
"""
from __future__ import annotations

import argparse
import contextlib
import dataclasses
import gc
import os
import sys
import threading
import time
import weakref
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import msgspec
import viser
from viser._messages import ViewerCameraMessage
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import ClientConnection, connect

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import loaders  # noqa: E402
from app.server import ExplorerServer  # noqa: E402
from app.session.explorer import Explorer  # noqa: E402
from app.session.settings import Settings  # noqa: E402
from app.tab import ClientSession  # noqa: E402

TARGET_MB = 30.0
"""Most growth over 300 edits the issue allows."""
SIGMA2 = (2.0, 3.0, 4.0)
CAMERA = ViewerCameraMessage(wxyz=(1.0, 0.0, 0.0, 0.0), position=(0.0, 0.0, 80.0), fov=0.9, near=0.01, far=1000.0,
                             image_height=900, image_width=1400, look_at=(0.0, 0.0, 0.0), up_direction=(0.0, 0.0, 1.0))
"""A browser's first camera report: viser counts a client as connected once it has sent one."""


def rss_mb() -> float:
    """This process's resident memory in MB (``/proc/self/statm``)."""
    pages = int(Path("/proc/self/statm").read_text().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 2**20


@contextlib.contextmanager
def headless_tab(server: ExplorerServer, timeout: float = 120.0) -> Iterator[ClientSession]:
    """A websocket client standing in for a browser tab, and its session once it drew its first frame;
    the connection is closed after."""
    connection = connect(f"ws://127.0.0.1:{server.server.get_port()}",
                         subprotocols=[f"viser-v{viser.__version__}"], max_size=None)
    reader = threading.Thread(target=_drain, args=(connection,), name="soak-reader", daemon=True)
    reader.start()
    connection.send(msgspec.msgpack.encode(CAMERA.as_serializable_dict()))
    try:
        yield _first_session(server, timeout)
    finally:
        connection.close()
        reader.join(timeout=10)


def _drain(connection: ClientConnection) -> None:
    with contextlib.suppress(ConnectionClosed, OSError):
        for _ in connection:
            pass


def _first_session(server: ExplorerServer, timeout: float) -> ClientSession:
    deadline = time.monotonic() + timeout
    while not any(s.last is not None for s in list(server.sessions.values())):
        if time.monotonic() > deadline:
            raise TimeoutError("the tab's first frame was not computed in time")
        time.sleep(0.05)
    return next(iter(server.sessions.values()))


def edit(session: ClientSession, k: int) -> None:
    """Edit ``k`` of the soak, waited for: a frame step or a sigma2 change, the inspector and the
    walkthrough following."""
    frames = len(session.explorer)
    if k % 2:
        session.apply(lambda s: dataclasses.replace(s, frame=(s.frame + 1) % frames))
    else:
        session.apply(lambda s: s.with_params("cbm", sigma2=SIGMA2[(k // 2) % len(SIGMA2)]))
    if not session.worker.wait_idle(timeout=120):
        raise TimeoutError(f"edit {k} was not answered in 120 s")
    session.controls.explore.inspect_anchor()
    session.controls.walkthrough.go(k % 9)


@dataclass(frozen=True)
class Soak:
    dataset: str
    edits: int
    before_mb: float
    after_mb: float
    released: bool
    """The closed tab's session was removed from the server and garbage-collected."""

    @property
    def growth_mb(self) -> float:
        return self.after_mb - self.before_mb


def soak(dataset: str, edits: int, warmup: int = 30) -> Soak:
    """RSS growth of the server over ``edits`` edits after ``warmup`` ones, on ``dataset``."""
    server = ExplorerServer(Explorer(loaders.open(dataset)), Settings(), port=0)
    try:
        with headless_tab(server) as session:
            for k in range(warmup):
                edit(session, k)
            gc.collect()
            before = rss_mb()
            for k in range(warmup, warmup + edits):
                edit(session, k)
            gc.collect()
            after = rss_mb()
            freed = weakref.ref(session)
            del session
        return Soak(dataset, edits, before, after, _released(server, freed))
    finally:
        server.stop()


def _released(server: ExplorerServer, freed: weakref.ref, timeout: float = 30.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        gc.collect()
        if not server.sessions and freed() is None:
            return True
        time.sleep(0.1)
    return False


def closed_rounds(dataset: str, rounds: int, edits: int, steps: int) -> list[float]:
    """The server's RSS (MB) at the start and after each of ``rounds`` tabs, opened, edited, stepped
    and closed in turn."""
    server = ExplorerServer(Explorer(loaders.open(dataset)), Settings(), port=0)
    try:
        gc.collect()
        sizes = [rss_mb()]
        for _ in range(rounds):
            with headless_tab(server) as session:
                for k in range(edits):
                    session.apply(lambda s, k=k: s.with_params("cbm", sigma2=1.0 + (k % 37) / 4))
                    _answered(session, k)
                frames = len(session.explorer)
                for k in range(steps):
                    session.apply(lambda s, n=frames: dataclasses.replace(s, frame=(s.frame + 1) % n))
                    _answered(session, k)
                freed = weakref.ref(session)
                del session
            _released(server, freed)
            gc.collect()
            sizes.append(rss_mb())
        return sizes
    finally:
        server.stop()


def _answered(session: ClientSession, k: int) -> None:
    if not session.worker.wait_idle(timeout=120):
        raise TimeoutError(f"edit {k} was not answered in 120 s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--datasets", nargs="+", default=["argoverse2", "synthetic:300"])
    parser.add_argument("--edits", type=int, default=300)
    parser.add_argument("--warmup", type=int, default=30)
    parser.add_argument("--rounds", type=int, default=0, help="tabs opened, edited and closed in turn")
    parser.add_argument("--steps", type=int, default=100, help="frame steps per round (--rounds)")
    args = parser.parse_args()
    if args.rounds:
        for dataset in args.datasets:
            sizes = closed_rounds(dataset, args.rounds, args.edits, args.steps)
            rounds = " -> ".join(f"{size:.0f}" for size in sizes)
            print(f"{dataset}: RSS (MB) at start and after each closed tab: {rounds} "
                  f"({sizes[-1] - sizes[1]:+.0f} MB after the first round)", flush=True)
        return
    print(f"{'dataset':<16} {'edits':>5} {'RSS before':>11} {'RSS after':>10} {'growth':>8}  tab freed on close")
    for dataset in args.datasets:
        result = soak(dataset, args.edits, args.warmup)
        verdict = "ok" if result.growth_mb <= TARGET_MB else f"over the {TARGET_MB:.0f} MB target"
        print(f"{dataset:<16} {result.edits:>5} {result.before_mb:>8.1f} MB {result.after_mb:>7.1f} MB "
              f"{result.growth_mb:>+5.1f} MB  {'yes' if result.released else 'NO'}  ({verdict})", flush=True)


if __name__ == "__main__":
    main()
