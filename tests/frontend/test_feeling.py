"""After a set, the patient says how it felt (issue 23, point 4): pain 0-10 and effort (Borg CR10) as large buttons,
with Skip; the answer is stored with the session and the therapist reads it on the session page."""

from __future__ import annotations

import uuid
from contextlib import closing

import pytest
from axe_playwright_python.sync_playwright import Axe
from playwright.sync_api import expect

from tests.backend.khs_files import make_khs
from tests.frontend.conftest import THERAPIST, api_client, login, open_page, shot
from tests.frontend.test_live_set import PASSWORD
from tests.frontend.test_never_silent import (
    EXERCISE,
    LOAD_MS,
    TARGET,
    AgentLink,
    _now_iso,
    patient_with_device,
    press_start,
)

pytestmark = pytest.mark.browser


def _assign_to_tara(base: str, pid: int) -> None:
    tara, _ = api_client(base, THERAPIST)
    admin, headers = api_client(base, "admin@demo.clinic")
    try:
        r = admin.put(f"/api/v1/patients/{pid}/therapists/{tara.get('/api/v1/users/me').json()['id']}", headers=headers)
    finally:
        admin.close()
        tara.close()
    assert r.status_code == 204, r.text


@pytest.mark.parametrize("width,height", [(1366, 900), (390, 844)])
def test_the_patient_says_how_the_set_felt_and_the_therapist_sees_it(browser, live_server, width, height):
    base = live_server.url
    email, pid, token = patient_with_device(base)
    _assign_to_tara(base, pid)
    link = AgentLink(base, token)
    with closing(link), open_page(browser, base, width, height) as page:
        start, sid = press_start(page, link, email), str(uuid.uuid4())
        link.progress(start, "ended", TARGET, sid, elapsed_s=9.0, reason="target")
        stored = link.upload(make_khs(EXERCISE, TARGET, seed=21, session_id=sid, created_at=_now_iso()))
        feeling = page.locator("#feeling")
        expect(feeling).to_be_visible(timeout=30_000)
        expect(page.locator("#feeling-save")).to_be_disabled()  # nothing chosen yet
        page.locator("#feeling-pain").get_by_role("button", name="3", exact=True).click()
        page.locator("#feeling-effort").get_by_role("button", name="4", exact=True).click()
        expect(page.locator("#feeling-pain button[aria-pressed=true]")).to_have_text("3")
        shot(page, f"feeling-{width}")
        bad = [v["id"] for v in Axe().run(page).response["violations"] if v["impact"] in ("serious", "critical")]
        assert not bad, bad
        page.locator("#feeling-save").click()
        expect(page.locator("#feeling-thanks")).to_contain_text("Thank you")
        r = link.client.get(f"/api/v1/sessions/{stored['id']}/feeling")
        assert (r.json()["pain"], r.json()["effort"]) == (3, 4.0), r.text
        assert not page.js_errors, page.js_errors
    with open_page(browser, base, width, height) as page:
        login(page, THERAPIST)
        page.wait_for_url("**/therapist")
        page.goto(f"/therapist/sessions/{stored['id']}")
        expect(page.locator("#session-feeling")).to_contain_text("pain 3 of 10", timeout=LOAD_MS)
        expect(page.locator("#session-feeling")).to_contain_text("effort 4 of 10 (Borg CR10)")


def test_a_set_recorded_without_the_live_panel_is_asked_under_the_last_exercise(browser, live_server):
    """A set the home computer (or the camera page) stored without the live panel open is asked about too, once:
    under "Your last exercise", until it is answered or skipped."""
    base = live_server.url
    email, _, token = patient_with_device(base)
    link = AgentLink(base, token)
    with closing(link), open_page(browser, base, 390, 844) as page:
        stored = link.upload(make_khs(EXERCISE, TARGET, seed=24, created_at=_now_iso()))  # no Start on the page
        login(page, email, PASSWORD)
        last = page.locator("#last-session")
        expect(last.locator("#last-sentence")).to_be_visible(timeout=LOAD_MS)
        expect(last.locator("#feeling")).to_be_visible()
        last.locator("#feeling-pain").get_by_role("button", name="6", exact=True).click()
        shot(page, "feeling-last-exercise-390")
        bad = [v["id"] for v in Axe().run(page).response["violations"] if v["impact"] in ("serious", "critical")]
        assert not bad, bad
        last.locator("#feeling-save").click()
        expect(last.locator("#feeling-thanks")).to_contain_text("Thank you")
        r = link.client.get(f"/api/v1/sessions/{stored['id']}/feeling")
        assert (r.json()["pain"], r.json()["effort"]) == (6, None), r.text
        page.reload()  # answered: not asked again
        expect(last.locator("#last-sentence")).to_be_visible(timeout=LOAD_MS)
        expect(page.locator("#feeling")).to_have_count(0)
        assert not page.js_errors, page.js_errors
