"""Response headers that tell browsers what the app's pages may do: a Content-Security-Policy per kind of page,
no framing by other sites, no MIME sniffing, no Referer to other sites, HSTS behind HTTPS, no caching of API data.

Three policies, chosen by path:
- the pages and the API (everything not below): scripts, styles and connections of this origin only; inline styles
  only (plotly.js sets them); nothing may frame it but this origin;
- viser's client (/replay/viewer/): it unpacks itself into an inline script, compiles WebAssembly and builds
  functions with Function() (Emscripten's embind), so it gets 'unsafe-inline' and 'unsafe-eval', and connections to
  this origin only: it fetches no recording, and opens no websocket, anywhere else. A recording can carry JavaScript
  (viser's RunJavascriptMessage, run with Function()), so what it may play is narrowed twice: the page answers only
  ?playbackPath=<a session's replay in this API> (frontend.pages.replay_viewer), and connect-src keeps it on this
  origin, where recordings are built by the server;
- the API documentation /docs (backend.api_docs): Swagger UI's files from this origin and the one inline script that
  starts it, connections to this origin only;
- the patient's camera page (/patient/camera): the page policy plus 'wasm-unsafe-eval', which compiling the pose
  landmarker's WebAssembly needs; connect-src stays 'self', so MediaPipe's usage-metrics call to another site is
  blocked. The landmarker's worker (/static/camera_pose_worker.js) gets the same policy: a worker is governed by
  its own script's CSP, and it is the worker that compiles the WebAssembly. No other page may compile WebAssembly.
"""

from __future__ import annotations

from starlette.datastructures import MutableHeaders
from starlette.types import ASGIApp, Message, Receive, Scope, Send

VIEWER_PATH = "/replay/viewer/"
DOCS_PATHS = frozenset({"/docs", "/docs/oauth2-redirect"})
CAMERA_PATH = "/patient/camera"
CAMERA_WORKER_PATH = "/static/camera_pose_worker.js"  # a worker's CSP is its own script's: it compiles the wasm

_COMMON = "base-uri 'none'; object-src 'none'; form-action 'self'; frame-ancestors 'self'"
PAGE_POLICY = (
    "default-src 'self'; script-src 'self'; style-src 'self' 'unsafe-inline'; img-src 'self' data: blob:; "
    f"font-src 'self' data:; connect-src 'self'; frame-src 'self'; worker-src 'self' blob:; {_COMMON}"
)
VIEWER_POLICY = (
    "default-src 'self'; script-src 'self' 'unsafe-inline' 'unsafe-eval'; style-src 'self' 'unsafe-inline'; "
    f"img-src 'self' data: blob:; font-src 'self' data:; connect-src 'self' data: blob:; worker-src 'self' blob:; "
    f"frame-src 'none'; {_COMMON}"
)
DOCS_POLICY = (
    "default-src 'self'; script-src 'self' 'unsafe-inline'; style-src 'self' 'unsafe-inline'; img-src 'self' data:; "
    f"font-src 'self' data:; connect-src 'self'; worker-src 'self' blob:; frame-src 'none'; {_COMMON}"
)
CAMERA_POLICY = PAGE_POLICY.replace("script-src 'self';", "script-src 'self' 'wasm-unsafe-eval';")
HSTS = "max-age=31536000"


def policy_for(path: str) -> str:
    """Returns the Content-Security-Policy of a path of the app (without the public URL's prefix)."""
    if path == VIEWER_PATH:
        return VIEWER_POLICY
    if path in DOCS_PATHS:
        return DOCS_POLICY
    if path in (CAMERA_PATH, CAMERA_WORKER_PATH):
        return CAMERA_POLICY
    return PAGE_POLICY


class SecurityHeaders:
    """ASGI middleware adding the module's headers to every HTTP answer (an answer's own Cache-Control stays);
    hsts: send Strict-Transport-Security (the public URL is https)."""

    def __init__(self, app: ASGIApp, hsts: bool) -> None:
        self.app = app
        self.hsts = hsts

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        path = scope["path"].removeprefix(scope.get("root_path", "")) or "/"
        api = path == "/api" or path.startswith("/api/")

        async def with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                headers = MutableHeaders(scope=message)
                headers["Content-Security-Policy"] = policy_for(path)
                headers["X-Frame-Options"] = "SAMEORIGIN"
                headers["X-Content-Type-Options"] = "nosniff"
                headers["Referrer-Policy"] = "same-origin"
                headers["Cross-Origin-Opener-Policy"] = "same-origin"
                if self.hsts:
                    headers["Strict-Transport-Security"] = HSTS
                if api and "cache-control" not in headers:
                    headers["Cache-Control"] = "no-store"  # health data: not kept by browsers or proxies
            await send(message)

        await self.app(scope, receive, with_headers)
