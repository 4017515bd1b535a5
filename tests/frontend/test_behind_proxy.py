"""The app behind a clinic's reverse proxy: HTTPS, a path prefix (/clinic), a second origin for the browser.

The proxy rewrites nothing, so every URL the pages build must come from COACH_PUBLIC_URL or be relative; the
login, the pages, the session page and the 3D replay all work through it, and no request leaves its origin.
"""

from __future__ import annotations

import re
from contextlib import contextmanager

import pytest
from playwright.sync_api import expect

from backend.demo import DEMO_PASSWORD
from tests.frontend.conftest import THERAPIST, free_port, open_page, run_server, shot
from tests.frontend.proxy import ProxyServer, self_signed_certificate

pytestmark = pytest.mark.browser
PREFIX = "/clinic"


@pytest.fixture(scope="module")
def public_url(live_server, tmp_path_factory):
    """The app (same database as live_server) behind an HTTPS proxy at https://127.0.0.1:PORT/clinic."""
    folder = tmp_path_factory.mktemp("proxy")
    port = free_port()
    public = f"https://127.0.0.1:{port}{PREFIX}"
    with run_server(
        live_server.database_url,
        folder,
        COACH_PUBLIC_URL=public,
        COACH_COOKIE_SECURE="true",
        COACH_STORAGE_DIR=live_server.storage_dir,
    ) as app:
        cert, key = self_signed_certificate(folder)
        with ProxyServer(app, PREFIX, port, cert, key):
            yield public


@contextmanager
def on_origin_only(browser, public_url: str):
    """Yields a page of a fresh browser context; on leaving, asserts that no request or websocket left public_url
    and that no script error happened."""
    requests: list[str] = []
    with open_page(browser, ignore_https_errors=True) as page:
        page.on("request", lambda r: requests.append(r.url))
        page.on("websocket", lambda ws: requests.append(ws.url))
        yield page
    foreign = [u for u in requests if not (u.startswith(public_url + "/") or u.startswith(("data:", "blob:")))]
    assert not foreign, f"requests that left {public_url}: {foreign}"
    assert not page.js_errors, page.js_errors


def test_therapist_works_through_the_proxy_and_the_replay_plays(browser, public_url, live_server):
    with on_origin_only(browser, public_url) as page:
        page.goto(f"{public_url}/therapist")  # not signed in: to the login page, with the way back
        page.wait_for_url(re.compile(re.escape(public_url) + r"/\?next="))
        page.fill("#email", THERAPIST)
        page.fill("#password", DEMO_PASSWORD)
        page.click("#login-submit")
        page.wait_for_url(f"{public_url}/therapist")
        page.goto(f"{public_url}/therapist/patients/{live_server.patient_id}")
        page.locator("#sessions tbody a", has_text="3D replay").first.click()
        page.wait_for_url(re.compile(re.escape(public_url) + r"/therapist/sessions/\d+/replay$"))
        page.frame_locator("#viewer").locator("canvas").first.wait_for(state="visible", timeout=30_000)
        page.wait_for_function(
            "() => [...document.querySelector('#viewer').contentDocument.querySelectorAll('input')]"
            ".some(i => /\\d/.test(i.value))", timeout=30_000)  # fmt: skip
        shot(page, "proxy-replay")
        page.get_by_role("link", name="Back to the session").click()
        page.wait_for_url(re.compile(re.escape(public_url) + r"/therapist/sessions/\d+$"))
        expect(page.locator(".js-plotly-plot").first).to_be_visible()
        shot(page, "proxy-session")


def test_api_docs_work_through_the_proxy_without_leaving_its_origin(browser, public_url):
    with on_origin_only(browser, public_url) as page:
        page.goto(f"{public_url}/docs")
        expect(page.locator(".opblock-summary-path", has_text="/api/v1/sessions").first).to_be_visible()
        expect(page.locator(".servers select option").first).to_have_text(PREFIX)  # "Try it out" goes through it
        shot(page, "proxy-api-docs")
