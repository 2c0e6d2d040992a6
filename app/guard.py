"""Which requests the server answers: by their ``Host`` header (no DNS rebinding) and, for the
WebSocket that carries a tab, their ``Origin`` (no page of another site or port drives the app).

The app has no accounts: whoever can open its WebSocket can read the scene and settings, save
presets and start long computations. A browser lets any page open a WebSocket to any address, sends
the page's origin with it, and sends the name it resolved as ``Host``. So (issue 50, item 2):

- ``Host`` must name this server: ``localhost``, an IP address (no rebinding goes through a
  literal address), the ``--host`` the server was started on, or a name given with
  ``--allow-host``. A page of ``attacker.example`` whose name was re-pointed at 127.0.0.1 sends
  ``Host: attacker.example`` and gets 421.
- A WebSocket's ``Origin``, when there is one (browsers always send it), must be the page the
  app served: the same host and port as the request's ``Host``, or loopback names on the same
  port (``localhost`` and ``127.0.0.1`` are one machine). Other pages get 403.

viser passes its own ``process_request`` (which serves the page's files) to websockets' ``serve``
and has no way to add a check; ``checking_requests`` builds viser's server with that function
wrapped (websockets calls it for every request, the WebSocket handshake included)."""
from __future__ import annotations

import contextlib
import http
import ipaddress
import threading
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from urllib.parse import urlsplit

import websockets.asyncio.server
from websockets.asyncio.server import ServerConnection
from websockets.http11 import Request, Response

LOOPBACK_NAMES = frozenset({"localhost"})
DEFAULT_PORTS = {"http": 80, "https": 443}
_STARTING = threading.Lock()
"""One viser server built at a time while ``serve`` is the checking one."""


def _address(name: str) -> ipaddress.IPv4Address | ipaddress.IPv6Address | None:
    try:
        return ipaddress.ip_address(name.split("%")[0])
    except ValueError:
        return None


def is_loopback_name(name: str) -> bool:
    """Whether ``name`` (lower case, no brackets) is this machine's loopback: ``localhost`` or a
    loopback address."""
    address = _address(name)
    return name in LOOPBACK_NAMES or (address is not None and address.is_loopback)


def host_and_port(authority: str, scheme: str = "http") -> tuple[str, int] | None:
    """``host:port`` (``[::1]:8080``) as a lower-case host without brackets and a port (the
    scheme's default when none is given), or None when it is not one."""
    try:
        parts = urlsplit(f"//{authority}")
        port = parts.port
    except ValueError:
        return None
    if not parts.hostname or parts.username is not None or parts.path or parts.query or parts.fragment:
        return None
    return parts.hostname.rstrip("."), port if port is not None else DEFAULT_PORTS.get(scheme, 80)


@dataclass(frozen=True)
class RequestGuard:
    """The names a request's ``Host`` may give (besides ``localhost`` and IP addresses): the host
    the server listens on and the ``--allow-host`` names."""

    names: frozenset[str]

    @classmethod
    def of(cls, bound_host: str, allowed: Iterable[str] = ()) -> RequestGuard:
        return cls(frozenset(name.strip().lower().strip("[]").rstrip(".") for name in (bound_host, *allowed)))

    def host_allowed(self, host: str) -> bool:
        return is_loopback_name(host) or _address(host) is not None or host in self.names

    def refusal(self, request: Request) -> tuple[http.HTTPStatus, str] | None:
        """Why ``request`` is refused (status and a line for the person who sent it), or None."""
        given = request.headers.get_all("Host")
        host = host_and_port(given[0]) if len(given) == 1 else None
        if host is None or not self.host_allowed(host[0]):
            shown = ", ".join(given)[:100]
            return (http.HTTPStatus.MISDIRECTED_REQUEST,
                    f"CBM Explorer does not answer to the host name {shown!r}; open it by its address, "
                    f"or start it with --allow-host NAME to use a name\n")
        origins = request.headers.get_all("Origin")
        origin = ", ".join(origins)
        if origins and (len(origins) > 1 or not self.origin_allowed(origin, host)):
            return http.HTTPStatus.FORBIDDEN, f"CBM Explorer accepts no connection from pages of {origin[:100]!r}\n"
        return None

    def origin_allowed(self, origin: str, host: tuple[str, int]) -> bool:
        """Whether a page of ``origin`` is the one this server served to the ``Host`` ``host``."""
        scheme, _, authority = origin.partition("://")
        if scheme not in DEFAULT_PORTS:
            return False
        page = host_and_port(authority, scheme)
        if page is None or not self.host_allowed(page[0]):
            return False
        return page == host or (page[1] == host[1] and is_loopback_name(page[0]) and is_loopback_name(host[0]))

    def wrap(self, process_request: Callable | None) -> Callable[[ServerConnection, Request], Response | None]:
        """``process_request`` (viser's: its files) behind this guard."""
        def checked(connection: ServerConnection, request: Request) -> Response | None:
            refused = self.refusal(request)
            if refused is not None:
                return connection.respond(*refused)
            return process_request(connection, request) if process_request is not None else None

        return checked


@contextlib.contextmanager
def checking_requests(guard: RequestGuard) -> Iterator[None]:
    """While inside, every websockets server built has its requests checked by ``guard`` first."""
    plain = websockets.asyncio.server.serve

    class Checked(plain):
        def __init__(self, *args, process_request: Callable | None = None, **kwargs) -> None:
            super().__init__(*args, process_request=guard.wrap(process_request), **kwargs)

    with _STARTING:
        websockets.asyncio.server.serve = Checked
        try:
            yield
        finally:
            websockets.asyncio.server.serve = plain
