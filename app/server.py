"""The viser server: one ``ClientSession`` per browser tab over the ``Explorer`` of the dataset it
shows (one per dataset, shared by the tabs showing it); a tab picks another dataset among those
offered (``app.session.datasets``) and its session is rebuilt on it, without a restart."""
from __future__ import annotations

import concurrent.futures
import errno
import gc
import ipaddress
import socket
import threading
from collections.abc import Iterable

import viser

from cbm import return_memory
from loaders import LoaderError

from .guard import RequestGuard, checking_requests
from .scene.presentation import THEME
from .session import kernels
from .session.datasets import Catalogue, DataError, Dataset, settings_on
from .session.explorer import Explorer
from .session.settings import Settings
from .session.start import runs_on, start_of
from .tab import ClientSession

RESOLVE_SECONDS = 5.0
"""How long a host name may take to resolve before the server gives up on it."""
START_SECONDS = 15.0
"""How long viser may take to start listening before the server gives up (it waits forever on an
address it cannot bind, trying the next 1000 ports)."""
CLOSE_SECONDS = 1.0
"""How long ``stop`` waits for the tabs' workers to finish what they compute."""
TITLE = "CBM Explorer"
TITLE_HTML = f'<img alt="" src="data:," style="display:none" onerror="document.title = {TITLE!r}">'
"""Names the browser tab: viser serves its page titled "Viser" and offers no way to change it, but
runs the handlers of the HTML it is given (an image that cannot load reports an error at once)."""


class AddressError(OSError):
    """A host that does not resolve or a port that is taken; the message says which and why."""


def resolve(host: str, port: int, timeout: float = RESOLVE_SECONDS) -> list[tuple]:
    """The socket addresses ``host:port`` stands for (``socket.getaddrinfo``), within ``timeout``."""
    pool = concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix="resolve")
    future = pool.submit(socket.getaddrinfo, host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE)
    pool.shutdown(wait=False)
    try:
        found = future.result(timeout=timeout)
    except concurrent.futures.TimeoutError:
        raise AddressError(f"the host {host!r} did not resolve within {timeout:.0f} s") from None
    except (OSError, UnicodeError) as error:
        raise AddressError(f"the host {host!r} does not resolve: {error}") from None
    return list(dict.fromkeys((family, address) for family, _, _, _, address in found))


def check_free(host: str, port: int) -> None:
    """``AddressError`` unless every address of ``host`` can be bound at ``port`` (0: any port), the way
    the server binds it (an IPv6 socket only for IPv6, as asyncio does: so an IPv4-mapped address
    such as ``::ffff:127.0.0.1`` cannot be bound)."""
    for family, address in resolve(host, port):
        with socket.socket(family, socket.SOCK_STREAM) as probe:
            probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            if family == socket.AF_INET6:
                probe.setsockopt(socket.IPPROTO_IPV6, socket.IPV6_V6ONLY, 1)
            try:
                probe.bind(address)
            except OSError as error:
                raise AddressError(bind_problem(address[0], port, error)) from None


def bind_problem(address: str, port: int, error: OSError) -> str:
    """Why ``address:port`` cannot be bound, in words, with what to try instead."""
    if error.errno == errno.EADDRINUSE:
        return f"port {port} on {address} is taken; choose another --port, or --port 0 for any free one"
    mapped = ipaddress.ip_address(address.split("%")[0])
    hint = f"; use --host {mapped.ipv4_mapped} instead" if getattr(mapped, "ipv4_mapped", None) else ""
    return f"the address {address} cannot be bound ({error.strerror or error}){hint}"


def host_port(host: str, port: int) -> str:
    """``host:port``, an IPv6 host in brackets (``[::1]:8080``) so that the port stays apart."""
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


def start_viser(host: str, port: int, verbose: bool, guard: RequestGuard | None = None,
                timeout: float = START_SECONDS) -> viser.ViserServer:
    """A viser server listening on ``host:port`` that answers only the requests ``guard`` lets
    through (by default: those for ``host`` or a loopback name), started in a helper thread:
    ``AddressError`` when it is not listening within ``timeout`` seconds (viser itself would wait
    forever)."""
    started: list[viser.ViserServer] = []
    failed: list[BaseException] = []

    def start() -> None:
        try:
            with checking_requests(guard or RequestGuard.of(host)):
                started.append(viser.ViserServer(host=host, port=port, label=TITLE, verbose=verbose))
        except BaseException as error:  # handed to the waiting thread below
            failed.append(error)

    thread = threading.Thread(target=start, name="viser-start", daemon=True)
    thread.start()
    thread.join(timeout)
    if failed:
        raise failed[0]
    if not started:
        raise AddressError(f"the server did not start listening on {host_port(host, port)} within {timeout:.0f} s")
    return started[0]


def is_loopback(host: str) -> bool:
    """Whether every address ``host`` resolves to is this machine's loopback."""
    return all(ipaddress.ip_address(address[0].split("%")[0]).is_loopback for _, address in resolve(host, 0))


class ExplorerServer:
    """Serves ``explorer`` on ``host:port`` (port 0: any free port), every tab starting from ``settings``
    on the first frame CBM can run on (``start_of``; ``start_note`` says when the frame moved).

    Only requests for this server's own names and WebSockets of its own page are answered
    (``app.guard``; ``allowed_hosts``: more names, ``--allow-host``). The address is checked first
    (``AddressError``: the host does not resolve, the port is taken); viser would otherwise move to
    the next free port without a word. CBM's compiled kernels are
    made ready in the background from the start (``kernels.prepare``); a tab's first recompute
    waits for them."""

    def __init__(self, explorer: Explorer, settings: Settings, host: str = "127.0.0.1", port: int = 8080,
                 verbose: bool = False, allowed_hosts: Iterable[str] = (), catalogue: Catalogue | None = None) -> None:
        check_free(host, port)
        self.explorer = explorer
        self.catalogue = catalogue or Catalogue(Dataset(explorer.sequence.name, explorer.sequence.name, "start"),
                                                explorer, shipped=False)
        """The datasets a tab may pick (``explorer``'s alone unless given)."""
        self.start_settings = settings
        self.settings, self.start_note = start_of(explorer, settings)
        self.kernels = kernels.prepare()
        self.sessions: dict[int, ClientSession] = {}
        self._gone: set[int] = set()
        """Tabs that closed while their session was still being built."""
        self._lock = threading.Lock()
        self.server = start_viser(host, port, verbose, RequestGuard.of(host, allowed_hosts))
        if port and self.server.get_port() != port:
            self.server.stop()
            raise AddressError(f"port {port} was taken while the server started; choose another --port")
        self.server.gui.configure_theme(**THEME)
        # Docked, the control panel covers no part of the scene's canvas: a camera framed for the
        # canvas needs only its aspect ratio, whatever the screen's pixel ratio (``layouts.screen_of``).
        self.server.gui.main_panel.dock_right()
        self.server.scene.set_up_direction("+z")
        # Plain lighting: no environment map (it washes the boxes' tops out, and costs most of a frame in
        # software WebGL) and no shadows (nothing casts one).
        self.server.scene.configure_environment_map(None)
        self.server.scene.configure_default_lights(enabled=True, cast_shadow=False)
        self.server.on_client_connect(self._connected)
        self.server.on_client_disconnect(self._disconnected)

    @property
    def url(self) -> str:
        """The address to open, an IPv6 host in brackets (``http://[::1]:8080``)."""
        return f"http://{host_port(self.server.get_host(), self.server.get_port())}"

    def _connected(self, client: viser.ClientHandle) -> None:
        self._open(client, self.catalogue.first, self.explorer, self.settings, self.start_note)

    def _open(self, client: viser.ClientHandle, name: str, explorer: Explorer, settings: Settings,
              note: str | None) -> None:
        """A new session of ``client`` on the dataset ``name``, under the title and the dataset picker
        (shown when more than one dataset is offered); ``note``: where it starts, when not on its frame."""
        client.gui.add_html(TITLE_HTML, order=-1.0)
        if len(self.catalogue.names) > 1:
            picker = client.gui.add_dropdown("dataset", self.catalogue.names, initial_value=name, order=-0.5,
                                             hint="the shipped scene and the datasets found in the data folders")

            def picked(event: viser.GuiEvent) -> None:
                if event.client is not None and picker.value != name:
                    threading.Thread(target=self._switch, args=(client, picker, name), name="open-dataset",
                                     daemon=True).start()

            picker.on_update(picked)
        session = ClientSession(client, explorer, settings, self.kernels)
        if note:
            moved = runs_on(explorer, settings, settings.frame)
            session.notify(f"Starting on frame {settings.frame}" if moved else "Too few objects seen by both agents",
                           note, "blue" if moved else "yellow")
        with self._lock:
            gone = client.client_id in self._gone
            self._gone.discard(client.client_id)
            if not gone:
                self.sessions[client.client_id] = session
        if gone:
            session.close()

    def _switch(self, client: viser.ClientHandle, picker: viser.GuiDropdownHandle, shown: str) -> None:
        """Rebuild ``client``'s session on the dataset its picker names (the ``Explorer`` opened on the
        first ask and shared), with its settings where the dataset offers them, on the first frame
        CBM can run on; a dataset that does not open is named in one line and the tab stays."""
        name = picker.value
        with self._lock:
            session = self.sessions.get(client.client_id)
        if session is None:
            return
        session.notify(f"Opening {name}", "this tab shows it when it is loaded", "blue")
        try:
            explorer = self.catalogue.explorer(name)
        except (DataError, LoaderError, OSError) as error:
            session.notify(f"{name} not opened", str(error).splitlines()[0], "red")
            picker.value = shown
            return
        settings, note = start_of(explorer, settings_on(session.settings, explorer, self.start_settings))
        with self._lock:
            if self.sessions.get(client.client_id) is not session:
                return
            del self.sessions[client.client_id]
        session.close()
        client.gui.reset()
        client.scene.reset()
        self._open(client, name, explorer, settings, note)

    def _disconnected(self, client: viser.ClientHandle) -> None:
        with self._lock:
            session = self.sessions.pop(client.client_id, None)
            if session is None:
                self._gone.add(client.client_id)
            last = not self.sessions
        if session is not None:
            session.close()
            del session
            self._release(last)

    def _release(self, last: bool) -> None:
        """After a tab closed: its objects collected and the memory handed back to the system; with
        no tab left, what the explorer kept for the tabs too (``Explorer.forget``). glibc keeps freed
        memory resident otherwise, and each new tab's grows it (issue 40: +200 MB a closed tab)."""
        gc.collect()
        if last:
            for explorer in self.catalogue.explorers:
                explorer.forget()
        else:
            return_memory()

    def stop(self) -> None:
        """Close every tab's session (waiting at most ``CLOSE_SECONDS`` for their workers) and the server."""
        with self._lock:
            sessions, self.sessions = list(self.sessions.values()), {}
        closing = [threading.Thread(target=s.close, name="close-session", daemon=True) for s in sessions]
        for thread in closing:
            thread.start()
        for thread in closing:
            thread.join(timeout=CLOSE_SECONDS / max(1, len(closing)))
        self.server.stop()
