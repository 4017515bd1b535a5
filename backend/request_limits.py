"""Checks every request makes before the app sees it: no NUL character in the URL or in JSON text (PostgreSQL
cannot store one, and no name, title or e-mail has one), and JSON bodies no larger than any form of the API.

Session uploads (application/octet-stream) are not read here: their route streams them with its own limit
(COACH_MAX_UPLOAD_BYTES). Answers: 400 InvalidInput (NUL in the URL), 422 InvalidInput (NUL in JSON text, or a
JSON body that is not UTF-8), 413 RequestTooLarge (declared or actual JSON body over the limit, refused before it is
read whole). The OpenAPI document lists these answers on every operation (backend.openapi).
"""

from __future__ import annotations

import json

from starlette.responses import JSONResponse
from starlette.types import ASGIApp, Message, Receive, Scope, Send

NUL_ESCAPE = b"\\u0000"  # the only way JSON can carry a NUL character


def has_nul(value: object) -> bool:
    """Returns whether a parsed JSON value holds a NUL character in any string or key."""
    if isinstance(value, str):
        return "\x00" in value
    if isinstance(value, dict):
        return any(has_nul(k) or has_nul(v) for k, v in value.items())
    if isinstance(value, list):
        return any(has_nul(v) for v in value)
    return False


def _error(status: int, error: str, detail: str) -> JSONResponse:
    return JSONResponse({"error": error, "detail": detail}, status_code=status)


def _not_utf8(body: bytes) -> JSONResponse | None:
    """Returns a 422 answer naming the first bad byte when a JSON body is not UTF-8 text, else None."""
    try:
        body.decode("utf-8")
    except UnicodeDecodeError as exc:
        return _error(422, "InvalidInput", f"body: JSON text must be UTF-8; byte {exc.start} is not")
    return None


class RequestLimits:
    """ASGI middleware applying the module's checks; max_json_bytes: the largest JSON body accepted."""

    def __init__(self, app: ASGIApp, max_json_bytes: int) -> None:
        self.app = app
        self.max_json_bytes = max_json_bytes

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        if "\x00" in scope["path"] or b"%00" in scope["query_string"] or b"\x00" in scope["query_string"]:
            await _error(400, "InvalidInput", "the URL contains a NUL character")(scope, receive, send)
            return
        headers = dict(scope["headers"])
        if not headers.get(b"content-type", b"").startswith(b"application/json"):
            await self.app(scope, receive, send)
            return
        body, refusal = await self._read(headers, receive)
        if refusal is None:
            refusal = _not_utf8(body)
        if refusal is None and NUL_ESCAPE in body and self._nul_in(body):
            refusal = _error(422, "InvalidInput", "text fields may not contain NUL characters (\\u0000)")
        if refusal is not None:
            await refusal(scope, receive, send)
            return
        await self.app(scope, _replay(body, receive), send)

    async def _read(self, headers: dict[bytes, bytes], receive: Receive) -> tuple[bytes, JSONResponse | None]:
        """Returns (the JSON body, None), or (b"", a 413 answer) once it is known to exceed the limit."""
        too_large = _error(413, "RequestTooLarge", f"JSON bodies are limited to {self.max_json_bytes} bytes")
        try:
            declared = int(headers.get(b"content-length", b"0"))
        except ValueError:
            declared = 0
        if declared > self.max_json_bytes:
            return b"", too_large
        parts, size = [], 0
        while True:
            message = await receive()
            if message["type"] != "http.request":
                break
            parts.append(message.get("body", b""))
            size += len(parts[-1])
            if size > self.max_json_bytes:
                return b"", too_large
            if not message.get("more_body", False):
                break
        return b"".join(parts), None

    @staticmethod
    def _nul_in(body: bytes) -> bool:
        try:
            return has_nul(json.loads(body))
        except (ValueError, RecursionError):
            return False  # not JSON the app can read either: it answers that itself


def _replay(body: bytes, receive: Receive) -> Receive:
    """Returns a receive() that hands the app the body read already, then passes on what comes next."""
    sent = False

    async def replay() -> Message:
        nonlocal sent
        if not sent:
            sent = True
            return {"type": "http.request", "body": body, "more_body": False}
        return await receive()

    return replay
