"""The therapist sees which language the patient reads (issue 23, point 2), in Chromium: "Reads: Deutsch" on the
patient's page, the system's suggestions marked as read by the patient in German, and beside the advice box and the
plan's note that free text reaches the patient untranslated; screenshots at 1366 and 390 px in /tmp/shots, checked
with axe-core at 390 px (tests/frontend/test_accessibility.py checks the page and its plan form at every width)."""

from __future__ import annotations

import uuid

import pytest
from axe_playwright_python.sync_playwright import Axe
from playwright.sync_api import expect

from backend.demo import DEMO_PASSWORD
from tests.backend.khs_files import make_khs
from tests.frontend.conftest import THERAPIST, api_client, open_page, shot, sign_in

pytestmark = pytest.mark.browser
HEIGHT = {1366: 900, 390: 844}


def _german_patient(base: str) -> int:
    """Creates a patient of the demo therapist who reads German (set by the therapist), with a set recorded and
    pain 8 of 10 said after it (a pending system suggestion); returns the patient's id."""
    email = f"reads-de-{uuid.uuid4().hex[:8]}@example.org"
    admin, headers = api_client(base, "admin@demo.clinic")
    try:
        body = {"email": email, "role": "patient", "password": DEMO_PASSWORD, "full_name": "Greta Gruber"}
        r = admin.post("/api/v1/users", json=body, headers=headers)
        assert r.status_code == 201, r.text
        pid = r.json()["id"]
    finally:
        admin.close()
    tara, headers = api_client(base, THERAPIST)
    patient, patient_headers = api_client(base, email)
    try:
        me = tara.get("/api/v1/users/me").json()["id"]
        admin, admin_headers = api_client(base, "admin@demo.clinic")
        assert admin.put(f"/api/v1/patients/{pid}/therapists/{me}", headers=admin_headers).status_code == 204
        admin.close()
        assert tara.patch(f"/api/v1/patients/{pid}", json={"locale": "de"}, headers=headers).json()["locale"] == "de"
        r = patient.post("/api/v1/sessions?exercise=squat", content=make_khs("squat", 3, seed=91),
                         headers=patient_headers | {"Content-Type": "application/octet-stream"})  # fmt: skip
        assert r.status_code == 201, r.text
        felt = patient.put(f"/api/v1/sessions/{r.json()['id']}/feeling", json={"pain": 8, "effort": 4},
                           headers=patient_headers)  # fmt: skip
        assert felt.status_code == 200, felt.text
    finally:
        tara.close()
        patient.close()
    return pid


def _serious(page) -> list[str]:
    return [v["id"] for v in Axe().run(page).response["violations"] if v["impact"] in ("serious", "critical")]


def test_the_therapist_sees_the_patients_language_and_that_free_text_is_not_translated(browser, live_server):
    pid = _german_patient(live_server.url)
    with open_page(browser, live_server.url, 1366, HEIGHT[1366]) as page:
        sign_in(page, THERAPIST)
        page.goto(f"/therapist/patients/{pid}")
        reads = page.locator("#patient-reads-language")
        expect(reads).to_have_text("Deutsch")
        expect(reads).to_have_attribute("lang", "de")
        expect(page.locator("#patient-reads")).to_contain_text("Reads: Deutsch")
        advice_note = page.locator("#suggestion-free-text")
        expect(advice_note).to_have_text(
            "Not translated: the patient reads Deutsch, and sees your advice exactly as you type it."
        )
        assert "suggestion-free-text" in (page.locator("#suggestion-text").get_attribute("aria-describedby") or "")
        expect(page.locator("#pending-language")).to_contain_text(
            "you see them in English, the patient reads them in Deutsch"
        )
        pending = page.locator("#pending li[data-suggestion-id]").first
        expect(pending.locator(".shown-in")).to_have_text(" · the patient reads it in Deutsch")
        page.click("#plan-new")
        plan_note = page.locator("#plan-free-text")
        expect(plan_note).to_be_visible()
        expect(plan_note).to_contain_text("the patient reads Deutsch, and sees the plan's title, note and hints")
        assert "plan-free-text" in (page.locator("#plan-notes").get_attribute("aria-describedby") or "")
        for width in (1366, 390):
            page.set_viewport_size({"width": width, "height": HEIGHT[width]})
            page.locator("#patient-reads").scroll_into_view_if_needed()
            shot(page, f"therapist-reads-de-{width}")
            scroll, client = page.evaluate("[document.documentElement.scrollWidth, "
                                           "document.documentElement.clientWidth]")  # fmt: skip
            assert scroll <= client, f"the page scrolls sideways at {width} px: {scroll} > {client}"
        assert not _serious(page)  # at 390 px with the plan form open (every width: test_accessibility)
        # the therapist leaves the choice to the patient's browser: the page says so at once
        page.locator("#patient-locale").select_option("")
        expect(reads).to_have_text("the language of their browser")
        assert reads.get_attribute("lang") is None
        expect(advice_note).to_have_text("Not translated: the patient sees your advice exactly as you type it.")
        assert not page.js_errors, page.js_errors
