"""Camera moves from two threads at once (a button's callback and another's) never leave the
browser at a pose neither asked for."""
from __future__ import annotations

import contextlib
import threading

import numpy as np

from app.scene.layouts import move_camera


class RecordingCamera:
    """viser's camera as far as a move goes: setting the position shifts the look-at with it, and
    every assignment is a message to the browser, which ends at the last position and look-at sent.
    ``on_position(n)`` runs after the n-th position is set."""

    def __init__(self, on_position) -> None:
        self._position, self._look_at = np.array([0.0, 0.0, 10.0]), np.zeros(3)
        self.sent: list[tuple[str, np.ndarray]] = []
        self.on_position, self.positions_set = on_position, 0

    @property
    def position(self) -> np.ndarray:
        return self._position

    @position.setter
    def position(self, value) -> None:
        offset = np.asarray(value, float) - self._position
        self._position = np.asarray(value, float)
        self.sent.append(("position", self._position))
        self.positions_set += 1
        self.on_position(self.positions_set)
        self.look_at = self._look_at + offset

    @property
    def look_at(self) -> np.ndarray:
        return self._look_at

    @look_at.setter
    def look_at(self, value) -> None:
        self._look_at = np.asarray(value, float)
        self.sent.append(("look_at", self._look_at))

    def browser_pose(self) -> tuple[tuple[float, ...], tuple[float, ...]]:
        last = {kind: tuple(value) for kind, value in self.sent}
        return last["position"], last["look_at"]


class Client:
    def __init__(self, camera: RecordingCamera) -> None:
        self.camera = camera

    def atomic(self):
        return contextlib.nullcontext()


def test_a_move_started_while_another_is_half_set_does_not_mix_with_it():
    reset = ((5.0, 0.0, 60.0), (8.0, 0.0, 0.0))
    panels = ((-28.0, 140.0, 190.0), (0.0, 224.0, 0.0))
    other = threading.Thread(target=lambda: move_camera(client, *panels))

    def start_the_other_move_midway(n: int) -> None:
        if n == 2:
            other.start()
            other.join(timeout=1.0)

    client = Client(RecordingCamera(start_the_other_move_midway))
    move_camera(client, *reset)
    other.join(timeout=30.0)
    assert not other.is_alive()
    assert client.camera.browser_pose() in (reset, panels)
