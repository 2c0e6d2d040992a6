"""The viser server: one ``ClientSession`` per browser tab over one shared ``Explorer``."""
from __future__ import annotations

import threading

import viser

from .scene.presentation import THEME
from .session import kernels
from .session.explorer import Explorer
from .session.settings import Settings
from .tab import ClientSession


class ExplorerServer:
    """Serves ``explorer`` on ``host:port`` (port 0: any free port), every tab starting from ``settings``.

    CBM's compiled kernels are made ready in the background from the start (``kernels.prepare``);
    a tab's first recompute waits for them."""

    def __init__(self, explorer: Explorer, settings: Settings, host: str = "127.0.0.1", port: int = 8080,
                 verbose: bool = False) -> None:
        self.explorer, self.settings = explorer, settings
        self.kernels = kernels.prepare()
        self.sessions: dict[int, ClientSession] = {}
        self._lock = threading.Lock()
        self.server = viser.ViserServer(host=host, port=port, label="CBM Explorer", verbose=verbose)
        self.server.gui.configure_theme(**THEME)
        self.server.scene.set_up_direction("+z")
        # Plain lighting: no environment map (it washes the boxes' tops out, and costs most of a frame in
        # software WebGL) and no shadows (nothing casts one).
        self.server.scene.configure_environment_map(None)
        self.server.scene.configure_default_lights(enabled=True, cast_shadow=False)
        self.server.on_client_connect(self._connected)
        self.server.on_client_disconnect(self._disconnected)

    @property
    def url(self) -> str:
        return f"http://{self.server.get_host()}:{self.server.get_port()}"

    def _connected(self, client: viser.ClientHandle) -> None:
        session = ClientSession(client, self.explorer, self.settings, self.kernels)
        with self._lock:
            self.sessions[client.client_id] = session

    def _disconnected(self, client: viser.ClientHandle) -> None:
        with self._lock:
            session = self.sessions.pop(client.client_id, None)
        if session is not None:
            session.close()

    def stop(self) -> None:
        with self._lock:
            sessions, self.sessions = list(self.sessions.values()), {}
        for session in sessions:
            session.close()
        self.server.stop()
