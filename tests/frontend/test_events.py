"""Pages update by themselves: an event raised by one server process reaches a page connected to another one.

Two replicas of the app share the PostgreSQL database (as docs/deployment.md scales it): a session uploaded through
replica A reaches the event stream, and the open patient page, served by replica B. PostgreSQL LISTEN/NOTIFY
carries it; process memory could not.
"""

from __future__ import annotations

import re
import threading

import httpx
import pytest
from playwright.sync_api import expect

from backend.demo import DEMO_PASSWORD
from tests.backend.khs_files import make_khs
from tests.frontend.conftest import login, run_server, shot

pytestmark = pytest.mark.browser
WALTER = "walter@demo.clinic"  # Paul's patient, no sessions in the other browser tests; plan: elbow flexion


@pytest.fixture(scope="module")
def replica(live_server, tmp_path_factory):
    """A second server process on live_server's database."""
    if not live_server.database_url.startswith("postgresql"):
        pytest.skip("replicas share events through PostgreSQL; the browser tests run on PostgreSQL in CI")
    with run_server(live_server.database_url, tmp_path_factory.mktemp("replica")) as base:
        yield base


def _signed_in(base: str, email: str) -> tuple[httpx.Client, dict]:
    client = httpx.Client(base_url=base, timeout=60)
    out = client.post("/api/v1/auth/login", json={"email": email, "password": DEMO_PASSWORD})
    out.raise_for_status()
    return client, {"X-CSRF-Token": out.json()["csrf_token"]}


def _upload(base: str, email: str, exercise: str, reps: int, seed: int) -> int:
    client, headers = _signed_in(base, email)
    try:
        r = client.post(f"/api/v1/sessions?exercise={exercise}", content=make_khs(exercise, reps, seed=seed),
                        headers=headers | {"Content-Type": "application/octet-stream"})  # fmt: skip
    finally:
        client.close()
    assert r.status_code == 201, r.text
    return r.json()["id"]


def test_a_session_stored_by_one_replica_reaches_the_event_stream_of_another(live_server, replica):
    client, _ = _signed_in(replica, WALTER)
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
    session_id = _upload(live_server.url, WALTER, "elbow_flexion", 5, seed=71)
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
    _upload(live_server.url, WALTER, "elbow_flexion", 3, seed=72)
    expect(page.locator("#last-sentence")).to_contain_text(re.compile(r"3 of 10"), timeout=15_000)
    assert page.locator("main").inner_text() != before
    shot(page, "patient_live_update")
    assert not [u for u in requests if u.endswith("/patient")][1:], "the page updated without reloading"
    assert not page.js_errors


def test_therapist_page_updates_when_advice_changes(page, live_server, replica):
    login(page, "physio@demo.clinic")  # Paul, Walter's therapist
    page.wait_for_url("**/therapist")
    page.goto(f"/therapist/patients/{_patient_id(live_server.url, WALTER)}")
    page.locator("#decided").wait_for()
    patient_id = _patient_id(live_server.url, WALTER)
    client, headers = _signed_in(replica, "physio@demo.clinic")
    try:
        text = "Lovely work this week. Keep the elbow close to your side."
        r = client.post(f"/api/v1/patients/{patient_id}/suggestions", json={"text": text}, headers=headers)
    finally:
        client.close()
    assert r.status_code == 201, r.text
    expect(page.locator("#decided")).to_contain_text("Keep the elbow close", timeout=15_000)


def _patient_id(base: str, email: str) -> int:
    client, _ = _signed_in(base, email)
    try:
        return client.get("/api/v1/users/me").json()["id"]
    finally:
        client.close()


def test_dashboard_updates_when_a_session_arrives(page, live_server, replica):
    login(page, "physio@demo.clinic")  # Paul, Walter's therapist
    page.wait_for_url("**/therapist")
    row = page.locator("#patients tbody tr", has_text="Walter Young")
    row.wait_for()
    page.wait_for_load_state("networkidle")
    before = row.inner_text()
    _upload(replica, WALTER, "elbow_flexion", 4, seed=73)
    expect(row).not_to_have_text(before, timeout=15_000)
    assert not page.js_errors
