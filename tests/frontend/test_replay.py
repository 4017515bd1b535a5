"""The 3D replay end to end: viser's client served by the app plays the session's recording in Chromium, every
request stays on the app's origin behind the login, and nobody else sees it."""

from __future__ import annotations

import re
import time

import pytest
from playwright.sync_api import expect

from tests.frontend.conftest import PATIENT, THERAPIST, login, newest_session_id, open_page, shot

pytestmark = pytest.mark.browser
OTHER_PATIENT = "george@demo.clinic"  # not Rose: may not see her sessions


def _canvas_png(page) -> bytes:
    return page.locator("#viewer").screenshot()


def _canvas_until(page, condition, timeout_s: float = 15.0) -> bool:
    """Returns whether the viewer's picture meets condition(png) within timeout_s (checked every 100 ms)."""
    deadline = time.monotonic() + timeout_s
    while not condition(_canvas_png(page)):
        if time.monotonic() > deadline:
            return False
        page.wait_for_timeout(100)
    return True


def _settled_canvas(page, timeout_s: float = 15.0) -> bytes:
    """Returns the viewer's picture once two pictures 100 ms apart are the same (the last frame drawn)."""
    last = _canvas_png(page)

    def same(png: bytes) -> bool:
        nonlocal last
        same, last = png == last, png
        return same

    assert _canvas_until(page, same, timeout_s), f"the picture kept changing for {timeout_s} s"
    return last


def test_therapist_replays_a_session_from_the_patient_page(page, live_server):
    requests: list[str] = []
    page.on("request", lambda r: requests.append(r.url))
    page.on("websocket", lambda ws: requests.append(ws.url))
    login(page, THERAPIST)
    page.wait_for_url("**/therapist")
    page.goto(f"/therapist/patients/{live_server.patient_id}")
    page.locator("#sessions tbody a", has_text="3D replay").first.click()
    page.wait_for_url(re.compile(r"/therapist/sessions/\d+/replay$"))
    expect(page.locator("#replay-title")).to_contain_text("·")
    viewer = page.frame_locator("#viewer")
    viewer.locator("canvas").first.wait_for(state="visible", timeout=30_000)
    page.wait_for_function(
        "() => [...document.querySelector('#viewer').contentDocument.querySelectorAll('input')]"
        ".some(i => /\\d/.test(i.value))", timeout=30_000)  # fmt: skip
    first = _canvas_png(page)
    assert _canvas_until(page, lambda png: png != first), "the picture must change while the replay plays"
    shot(page, "replay")
    viewer.locator("button:has(.tabler-icon-player-pause-filled)").click()  # pause: the picture holds still
    viewer.locator("button:has(.tabler-icon-binary-tree-2)").click()  # the scene tree: each skeleton is switched
    raw_eye = viewer.locator('[data-scene-node="/raw"] .tabler-icon-eye')
    raw_eye.wait_for()
    paused = _settled_canvas(page)
    assert paused == _canvas_png(page), "paused: the picture stays the same"
    raw_eye.click()
    viewer.locator('[data-scene-node="/raw"] .tabler-icon-eye-off').wait_for()
    assert _canvas_until(page, lambda png: png != paused), "hiding the raw skeleton changes the picture"
    shot(page, "replay-filtered-only")
    origin = live_server.url
    foreign = [u for u in requests if not u.startswith((origin + "/", "data:", "blob:"))]
    assert not foreign, f"requests off the app's origin: {foreign}"
    data_urls = sorted({u for u in requests if "/api/" in u or "/replay/viewer/" in u or "/replay" in u})
    assert any(u.endswith("/replay") and "/api/v1/sessions/" in u for u in data_urls), data_urls
    assert not page.js_errors, page.js_errors


def test_replay_urls_are_401_without_login(browser, live_server):
    with open_page(browser, live_server.url) as page:
        sid = _a_session_of_rose(live_server)
        for path in (f"/therapist/sessions/{sid}/replay", "/replay/viewer/?playbackPath=x",
                     f"/api/v1/sessions/{sid}/replay", f"/api/v1/sessions/{sid}"):  # fmt: skip
            response = page.request.get(path)
            assert response.status == 401, f"{path}: {response.status}"
        page.goto(f"/therapist/sessions/{sid}/replay")
        expect(page.get_by_role("link", name="Sign in")).to_be_visible()


def test_another_patient_gets_404_for_the_replay(page, live_server):
    sid = _a_session_of_rose(live_server)
    login(page, OTHER_PATIENT)
    page.wait_for_url("**/patient")
    response = page.goto(f"/therapist/sessions/{sid}/replay")
    assert response.status == 404  # the same as for a session that is not there
    expect(page.locator("h1")).to_contain_text("Session not found")
    assert page.request.get(f"/api/v1/sessions/{sid}/replay").status == 404
    assert page.locator("#viewer").count() == 0


def _a_session_of_rose(live_server) -> int:
    return newest_session_id(live_server.url, PATIENT)
