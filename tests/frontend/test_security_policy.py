"""The pages under their Content-Security-Policy in Chromium: everything they show still works (charts, the 3D
replay) with no violation reported, and another site cannot frame them (backend.security_headers)."""

from __future__ import annotations

import re
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import pytest

from tests.frontend.conftest import PATIENT, THERAPIST, login, newest_session_id, shot

pytestmark = pytest.mark.browser
REPORT_VIOLATIONS = """document.addEventListener("securitypolicyviolation",
  (e) => (window.__violations = window.__violations || []).push(`${e.violatedDirective} ${e.blockedURI}`), true);"""


def _violations(page) -> list[str]:
    found = []
    for frame in page.frames:
        found += frame.evaluate("() => window.__violations || []")
    return found


def test_therapist_pages_run_under_their_policy(page, live_server):
    page.context.add_init_script(REPORT_VIOLATIONS)
    login(page, THERAPIST)
    page.wait_for_url("**/therapist")
    sid = newest_session_id(live_server.url, THERAPIST, live_server.patient_id)
    for path, ready in [("/therapist", "#patients tbody tr"),
                        (f"/therapist/patients/{live_server.patient_id}", ".js-plotly-plot"),
                        (f"/therapist/sessions/{sid}", "#strip .js-plotly-plot")]:  # fmt: skip
        page.goto(path)
        page.locator(ready).first.wait_for()
        assert not _violations(page), f"{path}: {_violations(page)}"
    shot(page, "policy-session")
    page.goto(f"/therapist/sessions/{sid}/replay")
    page.frame_locator("#viewer").locator("canvas").first.wait_for(state="visible", timeout=30_000)
    page.wait_for_function(  # the recording is loaded and playing: its timeline shows a frame number
        "() => [...document.querySelector('#viewer').contentDocument.querySelectorAll('input')]"
        ".some(i => /\\d/.test(i.value))", timeout=30_000)  # fmt: skip
    page.wait_for_load_state("networkidle")
    assert not _violations(page), _violations(page)
    assert not page.js_errors, page.js_errors


def test_patient_page_runs_under_its_policy(page, live_server):
    page.context.add_init_script(REPORT_VIOLATIONS)
    login(page, PATIENT)
    page.wait_for_url("**/patient")
    page.locator(".js-plotly-plot").first.wait_for()
    assert not _violations(page), _violations(page)
    assert not page.js_errors, page.js_errors
    shot(page, "policy-patient")


def test_api_docs_run_under_their_policy(page, live_server):
    page.context.add_init_script(REPORT_VIOLATIONS)
    page.goto("/docs")
    page.locator(".opblock-summary-path").first.wait_for()
    assert not _violations(page), _violations(page)
    assert not page.js_errors, page.js_errors


@pytest.fixture(scope="module")
def framing_site():
    """Another site on 127.0.0.1: /frame?URL is a page that shows URL in an iframe (to lay its buttons over it)."""

    class Handler(BaseHTTPRequestHandler):
        def do_GET(self):  # noqa: N802 - http.server's name
            target = self.path.removeprefix("/frame?")
            body = f'<iframe id="victim" src="{target}" width="900" height="700"></iframe>'.encode()
            self.send_response(200)
            self.send_header("Content-Type", "text/html")
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, *args):
            pass

    httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    threading.Thread(target=httpd.serve_forever, daemon=True).start()
    try:
        yield f"http://127.0.0.1:{httpd.server_address[1]}"
    finally:
        httpd.shutdown()
        httpd.server_close()


@pytest.mark.parametrize("path", ["/patient", "/therapist", "/"])
def test_another_site_cannot_frame_the_pages(page, live_server, framing_site, path):
    """Framed under another site's buttons, a patient could be made to press Start, or a therapist Approve."""
    login(page, PATIENT if path == "/patient" else THERAPIST)
    page.wait_for_url(re.compile(r"/(patient|therapist)$"))
    page.goto(f"{framing_site}/frame?{live_server.url}{path}")  # waits for the load event: the frame's too
    page.wait_for_load_state("networkidle")
    assert page.frame_locator("#victim").locator("header.top").count() == 0, f"{path} shown inside another site"
