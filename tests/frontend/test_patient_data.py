"""The patient's data on the pages: the patient downloads it; an admin erases a patient after two confirmations."""

from __future__ import annotations

import uuid

import pytest
from axe_playwright_python.sync_playwright import Axe

from tests.frontend.conftest import PATIENT, SHOTS, api_client, login, shot

pytestmark = pytest.mark.browser
ADMIN = "admin@demo.clinic"


def test_the_patient_asks_for_all_their_data_sees_progress_then_downloads_it(page, live_server):
    login(page, PATIENT)
    page.wait_for_url("**/patient")
    ask = page.get_by_role("button", name="Prepare all my data for download")
    ask.click()  # a worker makes the archive (the server's embedded worker here); the page says where it is
    state = page.locator("#archive-state")
    state.wait_for(state="visible")
    shot(page, "archive-asked")
    link = page.get_by_role("link", name="Download all my data")
    link.wait_for(state="visible", timeout=180_000)
    assert "Made " in state.inner_text() and "sessions" in state.inner_text(), state.inner_text()
    href = link.get_attribute("href")
    assert href.startswith(f"/api/v1/patients/{live_server.patient_id}/archive?sha256="), "relative, same origin"
    shot(page, "archive-ready")
    with page.expect_download() as info:
        link.click()
    assert info.value.suggested_filename.startswith(f"patient-{live_server.patient_id}-data-")
    page.reload()  # the archive is kept: the page shows it at once, without asking again
    page.get_by_role("link", name="Download all my data").wait_for(state="visible")
    assert not page.get_by_role("button", name="Prepare all my data for download").is_visible()
    violations = [v for v in Axe().run(page).response["violations"] if v["impact"] in ("serious", "critical")]
    assert not violations, violations
    assert not page.js_errors


def test_an_admin_erases_a_patient_after_two_confirmations(page, live_server):
    client, csrf = api_client(live_server.url, ADMIN)
    email = f"erase-{uuid.uuid4().hex[:8]}@example.org"
    created = client.post("/api/v1/users", json={"email": email, "role": "patient", "password": "0123456789",
                                                 "full_name": "Erin Erase"}, headers=csrf)  # fmt: skip
    assert created.status_code == 201, created.text
    pid = created.json()["id"]
    login(page, ADMIN)
    page.wait_for_url("**/therapist")
    page.goto(f"/therapist/patients/{pid}")
    page.click("#erase-start")
    assert page.locator("#erase-continue").is_disabled()  # first confirmation: the checkbox
    page.check("#erase-understand")
    page.click("#erase-continue")
    assert page.locator("#erase-confirm").is_disabled()  # second: the e-mail typed again
    page.fill("#erase-email", "someone-else@example.org")
    assert page.locator("#erase-confirm").is_disabled()
    page.fill("#erase-email", email)
    violations = [v for v in Axe().run(page).response["violations"] if v["impact"] in ("serious", "critical")]
    assert not violations, violations
    for width in (1366, 768, 390):
        page.set_viewport_size({"width": width, "height": 900})
        shot(page, f"erase-step2-{width}")
    page.click("#erase-confirm")
    page.wait_for_selector("#erase-msg.note")
    assert "The patient was erased" in page.inner_text("#erase-msg")
    assert client.get(f"/api/v1/patients/{pid}").status_code == 404
    client.close()
    assert not page.js_errors


def test_the_patient_page_prints_without_buttons_and_links_the_pdf_report(page, live_server):
    from tests.frontend.conftest import THERAPIST

    login(page, THERAPIST)
    page.wait_for_url("**/therapist")
    page.goto(f"/therapist/patients/{live_server.patient_id}")
    page.wait_for_selector("#sessions tbody tr[data-session-id]")
    form = page.get_by_role("form", name="Progress report (PDF)")  # the form's own GET, as without its script
    response = page.request.get(form.get_attribute("action"))
    assert response.ok and response.headers["content-type"] == "application/pdf"
    page.emulate_media(media="print")
    assert not page.locator("#plan-new").is_visible() and not page.locator("header.top .btn").first.is_visible()
    assert not page.get_by_text("Time zone of the patient's reminder times").is_visible()  # no control's label alone
    for paper in ("A4", "Letter"):
        pdf = page.pdf(format=paper, print_background=False)
        (SHOTS / f"patient-page-{paper}.pdf").write_bytes(pdf)
    assert not page.js_errors
