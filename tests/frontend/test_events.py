"""Pages update by themselves: an event raised by one server process reaches a page connected to another one.

Two replicas of the app share the PostgreSQL database (as docs/deployment.md scales it): a session uploaded through
replica A reaches the event stream, and the open patient page, served by replica B. PostgreSQL LISTEN/NOTIFY
carries it; process memory could not.
"""

from __future__ import annotations

import re
import threading

import pytest
from playwright.sync_api import expect

from backend.demo import DEMO_PASSWORD
from tests.frontend.conftest import api_client, login, run_server, shot, upload_session

pytestmark = pytest.mark.browser
WALTER = "walter@demo.clinic"  # Paul's patient, no sessions in the other browser tests; plan: elbow flexion


@pytest.fixture(scope="module")
def replica(live_server, tmp_path_factory):
    """A second server process on live_server's database."""
    if not live_server.database_url.startswith("postgresql"):
        pytest.skip("replicas share events through PostgreSQL; the browser tests run on PostgreSQL in CI")
    with run_server(
        live_server.database_url, tmp_path_factory.mktemp("replica"), COACH_STORAGE_DIR=live_server.storage_dir
    ) as base:
        yield base


def test_a_session_stored_by_one_replica_reaches_the_event_stream_of_another(live_server, replica):
    client, _ = api_client(replica, WALTER)
    lines: list[str] = []
    connected = threading.Event()

    def listen() -> None:
        with client.stream("GET", "/api/v1/events", timeout=30) as stream:
            assert stream.headers["content-type"].startswith("text/event-stream")
            for line in stream.iter_lines():
                lines.append(line)
                connected.set()
                if line.startswith("data:"):
                    return

    reader = threading.Thread(target=listen, daemon=True)
    reader.start()
    assert connected.wait(10), "the event stream did not open"
    session_id = upload_session(live_server.url, WALTER, "elbow_flexion", 5, seed=71)["id"]
    reader.join(timeout=15)
    client.close()
    data = [line for line in lines if line.startswith("data:")]
    assert "event: session.stored" in lines, lines
    assert data and f'"session_id":{session_id}' in data[0], data


def test_patient_page_on_one_replica_shows_a_session_uploaded_through_another(page, live_server, replica):
    requests: list[str] = []
    page.on("request", lambda r: requests.append(r.url))
    page.goto(f"{replica}/")
    page.fill("#email", WALTER)
    page.fill("#password", DEMO_PASSWORD)
    page.click("#login-submit")
    page.wait_for_url(f"{replica}/patient")
    page.wait_for_load_state("networkidle")
    before = page.locator("main").inner_text()
    upload_session(live_server.url, WALTER, "elbow_flexion", 3, seed=72)
    expect(page.locator("#last-sentence")).to_contain_text(re.compile(r"3 of 10"), timeout=15_000)
    assert page.locator("main").inner_text() != before
    shot(page, "patient_live_update")
    assert not [u for u in requests if u.endswith("/patient")][1:], "the page updated without reloading"
    assert not page.js_errors


def test_therapist_page_updates_when_advice_changes(page, live_server, replica):
    login(page, "physio@demo.clinic")  # Paul, Walter's therapist
    page.wait_for_url("**/therapist")
    patient_id = _walter_id(live_server)
    page.goto(f"/therapist/patients/{patient_id}")
    page.locator("#decided").wait_for()
    client, headers = api_client(replica, "physio@demo.clinic")
    try:
        text = "Lovely work this week. Keep the elbow close to your side."
        r = client.post(f"/api/v1/patients/{patient_id}/suggestions", json={"text": text}, headers=headers)
    finally:
        client.close()
    assert r.status_code == 201, r.text
    expect(page.locator("#decided")).to_contain_text("Keep the elbow close", timeout=15_000)


def _walter_id(live_server) -> int:
    client, _ = api_client(live_server.url, WALTER)
    try:
        return client.get("/api/v1/users/me").json()["id"]
    finally:
        client.close()
