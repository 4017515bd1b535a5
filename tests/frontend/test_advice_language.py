"""Advice in the patient's language now, not the one of the day the rule ran (issue 23): a rule's advice made while
the patient read English shows in German on their page, in Chromium, once they choose German with the header's
Language select; a full-page screenshot at 1366, 768 and 390 px of each in /tmp/shots."""

from __future__ import annotations

import pytest
from axe_playwright_python.sync_playwright import Axe
from playwright.sync_api import expect

from tests.backend.khs_files import make_khs
from tests.frontend.conftest import (
    NEW_PATIENT_PASSWORD,
    THERAPIST,
    api_client,
    create_patient,
    open_page,
    shot,
    sign_in,
)
from tests.frontend.test_never_silent import LOAD_MS

pytestmark = pytest.mark.browser
PASSWORD = NEW_PATIENT_PASSWORD
ENGLISH = "you said your pain was 8 of 10"
GERMAN = "Schmerzen von 8 von 10"
HEIGHT = {1366: 900, 768: 1024, 390: 844}


def _new_patient(base: str) -> tuple[str, int]:
    """Creates a patient (no language chosen) assigned to the demo therapist; returns (e-mail, id)."""
    new = create_patient(base, "advice-lang", "Lena Lang", therapist=THERAPIST)
    return new.email, new.id


def _pain_advice(page, base: str, csrf: str, pid: int) -> None:
    """The signed-in patient records a set and says pain 8 of 10; the therapist approves the rule's advice."""
    upload = {"X-CSRF-Token": csrf, "Content-Type": "application/octet-stream"}
    r = page.context.request.post("/api/v1/sessions?exercise=squat", data=make_khs("squat", 3, seed=77), headers=upload)
    assert r.status == 201, r.text()
    felt = page.context.request.put(f"/api/v1/sessions/{r.json()['id']}/feeling", data={"pain": 8, "effort": 4},
                                    headers={"X-CSRF-Token": csrf})  # fmt: skip
    assert felt.ok, felt.text()
    tara, headers = api_client(base, THERAPIST)
    try:
        pending = tara.get(f"/api/v1/patients/{pid}/suggestions", params={"status": "pending"}, headers=headers)
        (advice,) = [s for s in pending.json()["items"] if s["rule"] == "pain_high"]
        assert ENGLISH in advice["text"], advice
        assert tara.post(f"/api/v1/suggestions/{advice['id']}/approve", headers=headers).status_code == 200
    finally:
        tara.close()


def _serious(page) -> list[str]:
    return [v["id"] for v in Axe().run(page).response["violations"] if v["impact"] in ("serious", "critical")]


def test_advice_made_in_english_shows_in_german_after_the_patient_chooses_german(browser, live_server):
    base = live_server.url
    email, pid = _new_patient(base)
    with open_page(browser, base, 1366, 900) as page:
        csrf = sign_in(page, email, PASSWORD)
        _pain_advice(page, base, csrf, pid)
        page.goto("/patient")
        advice = page.locator("#advice")
        expect(advice).to_contain_text(ENGLISH, timeout=LOAD_MS)
        shot(page, "advice-lang-en-1366")
        with page.expect_navigation():
            page.locator("header #language").select_option("de")
        expect(advice).to_contain_text(GERMAN, timeout=LOAD_MS)
        assert ENGLISH not in advice.inner_text()
        for width in (1366, 768, 390):
            page.set_viewport_size({"width": width, "height": HEIGHT[width]})
            page.reload()
            expect(advice).to_contain_text(GERMAN, timeout=LOAD_MS)
            shot(page, f"advice-lang-de-{width}")
            scroll, client = page.evaluate("[document.documentElement.scrollWidth, "
                                           "document.documentElement.clientWidth]")  # fmt: skip
            assert scroll <= client, f"the page scrolls sideways at {width} px: {scroll} > {client}"
        assert not _serious(page)
        assert not page.js_errors, page.js_errors
