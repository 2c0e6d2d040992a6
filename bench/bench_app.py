"""Recompute latency of the app: from a slider change to the new arrays being sent.

Starts the app's server on a free loopback port and connects one headless websocket client (no
browser: it announces a camera, as a browser does on connecting, and drains what the server sends).
Then it moves that tab's controls the way a browser does, by sending the GUI update messages a
moved slider sends, and times each change until the tab's worker has computed the trial, run CBM,
built the drawing and flushed the messages to the socket.

    python bench/bench_app.py [--dataset argoverse2] [--changes 60]
"""
from __future__ import annotations

import argparse
import statistics
import sys
import threading
import time
from pathlib import Path

import msgspec
import numpy as np
import viser
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from viser import _messages  # noqa: E402

import loaders  # noqa: E402
from app.server import ExplorerServer  # noqa: E402
from app.session.explorer import Explorer  # noqa: E402
from app.session.presets import discover  # noqa: E402
from app.session.settings import Settings  # noqa: E402


def headless_client(url: str):
    """A websocket client that looks like a browser tab to viser, draining everything it is sent."""
    socket = connect(url.replace("http://", "ws://"), subprotocols=[f"viser-v{viser.__version__}"], max_size=None)
    camera = _messages.ViewerCameraMessage(wxyz=(1.0, 0.0, 0.0, 0.0), position=(0.0, 0.0, 80.0), fov=1.0,
                                           near=0.01, far=1000.0, image_height=900, image_width=1400,
                                           look_at=(0.0, 0.0, 0.0), up_direction=(0.0, 0.0, 1.0))
    socket.send(msgspec.msgpack.encode(camera.as_serializable_dict()))
    received = [0]

    def drain() -> None:
        try:
            for message in socket:
                received[0] += len(message)
        except ConnectionClosed:
            pass

    threading.Thread(target=drain, daemon=True).start()
    return socket, received


def send_edit(socket, control, value) -> None:
    """What a browser sends when a person moves ``control`` to ``value``."""
    message = _messages.GuiUpdateMessage(control._impl.uuid, {"value": value})
    socket.send(msgspec.msgpack.encode(message.as_serializable_dict()))


def timed_changes(session, socket, control, values, settle) -> list[float]:
    """Milliseconds from sending each value of ``control`` until the worker has sent the result."""
    times = []
    for value in values:
        start = time.perf_counter()
        send_edit(socket, control, value)
        deadline = time.monotonic() + 30
        while not settle(session, value):
            assert time.monotonic() < deadline, "the edit never reached the tab"
            time.sleep(0.0005)
        assert session.worker.wait_idle(timeout=30), "recompute did not finish"
        times.append(1000 * (time.perf_counter() - start))
    return times


def report(name: str, times: list[float]) -> None:
    print(f"{name:<34} median {statistics.median(times):6.1f} ms   worst {max(times):6.1f} ms   "
          f"({len(times)} changes)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dataset", default="argoverse2")
    parser.add_argument("--changes", type=int, default=60)
    args = parser.parse_args()

    explorer = Explorer(loaders.open(args.dataset))
    presets, _ = discover()
    server = ExplorerServer(explorer, presets["default"].apply(Settings()), port=0)
    socket, received = headless_client(server.url)
    try:
        deadline = time.monotonic() + 30
        while not server.sessions or next(iter(server.sessions.values())).last is None:
            assert time.monotonic() < deadline, "the headless client never got its first frame"
            time.sleep(0.05)
        session = next(iter(server.sessions.values()))
        sigma2 = session.controls.method.params[("cbm", "sigma2")]
        frame = session.controls.frame.frame
        timed_changes(session, socket, sigma2, [2.0, 3.0], lambda s, v: s.settings.cbm.sigma2 == v)

        grid = [0.25 * k for k in range(2, 25)]
        values = [grid[i % len(grid)] for i in range(args.changes)]
        sigma_times = timed_changes(session, socket, sigma2, values, lambda s, v: s.settings.cbm.sigma2 == v)
        frames = [int(k) for k in np.linspace(1, len(explorer) - 1, args.changes)]
        frames = [k for i, k in enumerate(frames) if i == 0 or k != frames[i - 1]]
        frame_times = timed_changes(session, socket, frame, frames, lambda s, v: s.settings.frame == v)

        print(f"scene: {explorer.sequence.name}, {len(explorer)} frames; one headless tab; "
              f"{received[0] / 1e6:.1f} MB sent to it")
        report("sigma2 slider -> arrays sent", sigma_times)
        report("frame slider -> arrays sent", frame_times)
        report("both", sigma_times + frame_times)
        print(f"(CBM alone on the last frame: {1000 * session.last.result.timings['total']:.1f} ms)")
    finally:
        socket.close()
        server.stop()


if __name__ == "__main__":
    main()
