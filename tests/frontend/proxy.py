"""A small HTTPS reverse proxy for tests, configured like a clinic's nginx in front of the app:

    location /clinic/ { proxy_pass http://127.0.0.1:APP/; proxy_set_header X-Forwarded-For ...; }

It strips the path prefix, passes the body and headers through, adds X-Forwarded-For/-Proto/-Host, and rewrites
nothing in the answers (no Location or HTML rewriting): whatever URL the app builds must already be right.
"""

from __future__ import annotations

import asyncio
import subprocess
import threading
from pathlib import Path

import httpx
import uvicorn

HOP_BY_HOP = {"connection", "keep-alive", "transfer-encoding", "te", "trailer", "upgrade", "proxy-authorization",
              "proxy-authenticate", "host", "content-length"}  # fmt: skip


class PrefixProxy:
    """ASGI app forwarding `prefix/...` to `upstream/...`; anything outside the prefix is 404."""

    def __init__(self, upstream: str, prefix: str) -> None:
        self.upstream = upstream.rstrip("/")
        self.prefix = prefix.rstrip("/")
        self.client: httpx.AsyncClient | None = None

    async def __call__(self, scope, receive, send) -> None:
        if scope["type"] == "lifespan":
            await self._lifespan(receive, send)
            return
        path = scope["path"]
        if scope["type"] != "http" or not path.startswith(self.prefix + "/"):
            await _answer(send, 404, [(b"content-type", b"text/plain")], b"not behind this proxy")
            return
        body = b""
        while True:
            message = await receive()
            body += message.get("body", b"")
            if not message.get("more_body"):
                break
        headers = [(k.decode(), v.decode()) for k, v in scope["headers"] if k.decode().lower() not in HOP_BY_HOP]
        host = dict(scope["headers"]).get(b"host", b"").decode()
        headers += [("X-Forwarded-For", scope["client"][0]), ("X-Forwarded-Proto", scope["scheme"]),
                    ("X-Forwarded-Host", host)]  # fmt: skip
        url = self.upstream + path[len(self.prefix) :]
        if scope["query_string"]:
            url += "?" + scope["query_string"].decode()
        assert self.client is not None
        request = self.client.build_request(scope["method"], url, headers=headers, content=body)
        resp = await self.client.send(request, stream=True)  # streamed through, as nginx does (event streams)
        try:
            out = [(k.encode(), v.encode()) for k, v in resp.headers.multi_items() if k.lower() not in HOP_BY_HOP]
            out = [(k, v) for k, v in out if k.lower() != b"content-encoding"]  # httpx decodes the body
            await send({"type": "http.response.start", "status": resp.status_code, "headers": out})
            async for chunk in resp.aiter_bytes():
                await send({"type": "http.response.body", "body": chunk, "more_body": True})
            await send({"type": "http.response.body", "body": b""})
        finally:
            await resp.aclose()

    async def _lifespan(self, receive, send) -> None:
        while True:
            message = await receive()
            if message["type"] == "lifespan.startup":
                self.client = httpx.AsyncClient(timeout=60, follow_redirects=False)
                await send({"type": "lifespan.startup.complete"})
            elif message["type"] == "lifespan.shutdown":
                if self.client is not None:
                    await self.client.aclose()
                await send({"type": "lifespan.shutdown.complete"})
                return


async def _answer(send, status: int, headers: list[tuple[bytes, bytes]], body: bytes) -> None:
    headers = [*headers, (b"content-length", str(len(body)).encode())]
    await send({"type": "http.response.start", "status": status, "headers": headers})
    await send({"type": "http.response.body", "body": body})


def self_signed_certificate(folder: Path) -> tuple[Path, Path]:
    """Returns (certificate, key) PEM files for 127.0.0.1, made with the openssl command."""
    cert, key = folder / "proxy.crt", folder / "proxy.key"
    subprocess.run(["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "1", "-subj", "/CN=127.0.0.1",
                    "-addext", "subjectAltName=IP:127.0.0.1", "-keyout", str(key), "-out", str(cert)],
                   check=True, capture_output=True)  # fmt: skip
    return cert, key


class ProxyServer:
    """Runs a PrefixProxy with TLS on 127.0.0.1:port in a background thread."""

    def __init__(self, upstream: str, prefix: str, port: int, cert: Path, key: Path) -> None:
        config = uvicorn.Config(PrefixProxy(upstream, prefix), host="127.0.0.1", port=port, log_level="warning",
                                ssl_certfile=str(cert), ssl_keyfile=str(key), lifespan="on")  # fmt: skip
        self.server = uvicorn.Server(config)
        self.thread = threading.Thread(target=lambda: asyncio.run(self.server.serve()), daemon=True)

    def __enter__(self) -> ProxyServer:
        self.thread.start()
        while not self.server.started:
            if not self.thread.is_alive():
                raise RuntimeError("the test proxy did not start")
            threading.Event().wait(0.05)
        return self

    def __exit__(self, *_exc) -> None:
        self.server.should_exit = True
        self.server.force_exit = True  # open event streams do not hold the shutdown
        self.thread.join(timeout=10)
