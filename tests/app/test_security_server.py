"""Issue 50, item 2: the server answers its own page only. A WebSocket from a page of another
origin is refused (403), and so is any request whose Host is not this server's name (421: DNS
rebinding); ``--allow-host`` adds a name. Real connections to a running server."""
from __future__ import annotations

import http.client
import socket
from pathlib import Path

import pytest
import viser
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

import loaders
from app.cli import parse
from app.guard import RequestGuard
from app.session.explorer import Explorer
from support import browser as ui

SUBPROTOCOL = f"viser-v{viser.__version__}"


@pytest.fixture(scope="module")
def tiny() -> Explorer:
    return Explorer(loaders.open("synthetic:4"))


def _get(port: int, host: str, path: str = "/") -> int:
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=30)
    connection.putrequest("GET", path, skip_host=True)
    connection.putheader("Host", host)
    connection.endheaders()
    status = connection.getresponse().status
    connection.close()
    return status


def _websocket(port: int, origin: str | None, host: str = "127.0.0.1") -> int:
    """101 when the handshake succeeds, else the status the server answered; ``host``: the name
    the client resolved (its Host header), the connection going to 127.0.0.1 whatever it is."""
    try:
        with connect(f"ws://{host}:{port}", origin=origin, subprotocols=[SUBPROTOCOL], open_timeout=30,
                     sock=socket.create_connection(("127.0.0.1", port), timeout=30)):
            return 101
    except InvalidStatus as refused:
        return refused.response.status_code


def test_a_websocket_from_a_page_of_another_origin_is_refused(tiny: Explorer, tmp_path: Path) -> None:
    with ui.scenario_server(tiny, tmp_path) as server:
        port = server.server.get_port()
        assert _websocket(port, "http://evil.example") == 403
        assert _websocket(port, f"http://localhost:{port + 1}") == 403
        assert _websocket(port, "null") == 403
        assert _websocket(port, f"http://127.0.0.1:{port}") == 101
        assert _websocket(port, f"http://localhost:{port}") == 101
        assert _websocket(port, None) == 101


def test_a_request_for_another_host_name_is_refused(tiny: Explorer, tmp_path: Path) -> None:
    with ui.scenario_server(tiny, tmp_path) as server:
        port = server.server.get_port()
        assert _get(port, "attacker.example") == 421
        assert _get(port, f"attacker.example:{port}") == 421
        assert _get(port, "") == 421
        assert _websocket(port, f"http://attacker.example:{port}", host="attacker.example") == 421
        assert [_get(port, f"{name}:{port}") for name in ("127.0.0.1", "localhost", "LOCALHOST", "[::1]")] == [200] * 4
        assert [_get(port, f"localhost:{port}", path) for path in ("/../../etc/passwd", "/%2e%2e/%2e%2e/etc/passwd",
                                                                 "/..%5c..%5cetc/passwd")] == [404] * 3


def test_allow_host_adds_a_name_for_a_lan(tiny: Explorer, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    assert parse(["--allow-host", "cbm.lan", "--allow-host", "Other.Lan"]).allow_host == ["cbm.lan", "Other.Lan"]
    from app.server import ExplorerServer
    from app.session.settings import Settings

    monkeypatch.setenv("CBM_EXPLORER_PRESETS", str(tmp_path))
    server = ExplorerServer(tiny, Settings(), port=0, allowed_hosts=["cbm.lan"])
    try:
        port = server.server.get_port()
        assert _get(port, f"cbm.lan:{port}") == 200 and _get(port, f"other.lan:{port}") == 421
        assert _websocket(port, f"http://cbm.lan:{port}", host="cbm.lan") == 101
        assert _websocket(port, f"http://cbm.lan:{port}") == 403
    finally:
        server.stop()


@pytest.mark.parametrize("origin, host, allowed", [
    ("http://127.0.0.1:8080", "127.0.0.1:8080", True), ("http://localhost:8080", "127.0.0.1:8080", True),
    ("http://[::1]:8080", "localhost:8080", True), ("https://localhost:8080", "localhost:8080", True),
    ("http://localhost:8081", "localhost:8080", False), ("http://192.168.1.5:8080", "127.0.0.1:8080", False),
    ("http://192.168.1.5:8080", "192.168.1.5:8080", True), ("file://", "localhost:8080", False),
    ("http://localhost.evil.example:8080", "localhost:8080", False),
    ("http://u@localhost:8080", "localhost:8080", False),
])
def test_the_origin_must_be_the_page_the_server_served(origin: str, host: str, allowed: bool) -> None:
    from app.guard import host_and_port

    assert RequestGuard.of("127.0.0.1").origin_allowed(origin, host_and_port(host)) is allowed
