"""The session page's downloads: a file a worker is still preparing (202) is said in words and downloads by itself
when it is ready; a build that failed for good is said, never saved as the download."""

from __future__ import annotations

import json

import pytest
from playwright.sync_api import expect

from tests.frontend.conftest import login, shot, upload_session

pytestmark = pytest.mark.browser

GEORGE = "george@demo.clinic"  # Paul's patient
PAUL = "physio@demo.clinic"


@pytest.fixture(scope="module")
def squat_session(live_server) -> int:
    """Uploads one short squat set as George; returns its id."""
    return upload_session(live_server.url, GEORGE, "squat", 2, seed=51, created_at="2026-11-21T09:30:00Z")["id"]


def test_a_file_being_prepared_is_said_then_downloads_by_itself(page, live_server, squat_session):
    login(page, PAUL)
    page.wait_for_url("**/therapist")
    asked = []

    def first_preparing(route):
        asked.append(route.request.url)
        if len(asked) == 1:  # as a long recording's first ask: a worker builds it
            route.fulfill(status=202, content_type="application/json", headers={"Retry-After": "1"},
                          body=json.dumps({"state": "preparing", "detail": "The file is queued; a worker will "
                                           "build it in a moment."}))  # fmt: skip
        else:
            route.continue_()

    page.route("**/api/v1/sessions/*/export?format=bvh", first_preparing)
    page.goto(f"/therapist/sessions/{squat_session}")
    expect(page.locator("#session-feeling")).not_to_be_empty()  # the last line above the downloads, filled
    state = page.locator("#download-state")
    with page.expect_download(timeout=30_000) as download:
        page.click("#downloads >> text=Motion (BVH)")
        expect(state).to_contain_text("The Motion (BVH) file is being prepared; it will download by itself")
        expect(state).to_have_class("note")
        shot(page, "session_download_preparing")
    assert download.value.suggested_filename == f"session-{squat_session}.bvh"
    assert download.value.path().read_bytes().startswith(b"HIERARCHY")
    expect(state).to_contain_text(f"session-{squat_session}.bvh was handed to the browser's downloads")
    assert len(asked) == 2, asked
    assert not page.js_errors, page.js_errors


def test_a_file_that_could_not_be_prepared_is_said_in_words(page, live_server, squat_session):
    login(page, PAUL)
    page.wait_for_url("**/therapist")
    words = "The session's file is missing from the object store (run `coach-server storage check`) (tried 6 times)"
    asked = []

    def failed(route):
        asked.append(route.request.url)
        route.fulfill(status=202, content_type="application/json", headers={"Retry-After": "1"},
                      body=json.dumps({"state": "failed", "detail": words}))  # fmt: skip

    page.route("**/api/v1/sessions/*/export?format=trc", failed)
    page.goto(f"/therapist/sessions/{squat_session}")
    expect(page.locator("#session-feeling")).not_to_be_empty()  # the last line above the downloads, filled
    downloads = []
    page.on("download", lambda d: downloads.append(d))
    page.click("#downloads >> text=Markers for OpenSim (TRC)")
    state = page.locator("#download-state")
    expect(state).to_have_text(f"The Markers for OpenSim (TRC) file could not be prepared. {words}")
    expect(state).to_have_class("alert")
    page.wait_for_timeout(1500)
    assert len(asked) == 1 and downloads == [], "a failed build is neither asked again nor saved"
    shot(page, "session_download_failed")
    assert not page.js_errors, page.js_errors
