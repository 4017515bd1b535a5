"""`coach-server serve` believes X-Forwarded-For only from COACH_FORWARDED_ALLOW_IPS (the command line's
--forwarded-allow-ips first): outside Docker too, a client next to the server cannot pose as another address."""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING, Any

from uvicorn.middleware.proxy_headers import ProxyHeadersMiddleware

from backend import cli
from backend.config import Settings

if TYPE_CHECKING:
    from uvicorn._types import ASGIReceiveEvent, ASGISendEvent, HTTPScope


def _client_seen(trusted: str, peer: str, forwarded: str) -> str:
    """Returns the client address the app sees behind uvicorn's proxy-header handling with these trusted proxies."""
    seen = {}

    async def app(scope, receive, send):
        seen["client"] = scope["client"][0]

    async def receive() -> ASGIReceiveEvent:
        raise AssertionError("the app reads no request body")

    async def send(message: ASGISendEvent) -> None:
        raise AssertionError("the app sends no response")

    scope: HTTPScope = {"type": "http", "asgi": {"version": "3.0", "spec_version": "2.3"}, "http_version": "1.1",
                        "client": (peer, 50000), "headers": [(b"x-forwarded-for", forwarded.encode())],
                        "scheme": "http", "server": ("127.0.0.1", 8000), "path": "/", "raw_path": b"/",
                        "query_string": b"", "root_path": "", "method": "GET"}  # fmt: skip
    asyncio.run(ProxyHeadersMiddleware(app, trusted_hosts=trusted)(scope, receive, send))
    return seen["client"]


def _options(argv: list[str]) -> dict[str, Any]:
    return cli.serve_options(cli.build_parser().parse_args(["serve", *argv]), Settings())


def test_serve_trusts_the_proxies_of_the_setting(monkeypatch):
    monkeypatch.setenv("COACH_FORWARDED_ALLOW_IPS", "10.9.9.9")
    options = _options([])
    assert options["forwarded_allow_ips"] == "10.9.9.9"
    assert _client_seen(options["forwarded_allow_ips"], "127.0.0.1", "6.6.6.6") == "127.0.0.1", "forged from local"
    assert _client_seen(options["forwarded_allow_ips"], "10.9.9.9", "6.6.6.6") == "6.6.6.6", "the proxy is believed"


def test_the_command_line_wins_and_the_default_is_the_loopback(monkeypatch):
    monkeypatch.delenv("COACH_FORWARDED_ALLOW_IPS", raising=False)
    assert _options([])["forwarded_allow_ips"] == "127.0.0.1"
    monkeypatch.setenv("COACH_FORWARDED_ALLOW_IPS", "10.9.9.9")
    assert _options(["--forwarded-allow-ips", "10.1.1.1"])["forwarded_allow_ips"] == "10.1.1.1"
