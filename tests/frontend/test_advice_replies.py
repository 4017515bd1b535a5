"""Messages both ways (issue 23, point 5): the patient answers advice with a large preset button, and the therapist's
dashboard shows the reply as unread without reloading; opening the patient's page marks it read, which the patient's
page shows by itself too."""

from __future__ import annotations

import uuid

import pytest
from axe_playwright_python.sync_playwright import Axe
from playwright.sync_api import expect

from tests.frontend.conftest import THERAPIST, api_client, login, open_page, shot
from tests.frontend.test_never_silent import LOAD_MS

pytestmark = pytest.mark.browser
PASSWORD = "reply-password-2026"
ADVICE = "Hold the top of each knee extension for two seconds."


def _patient_with_advice(base: str) -> tuple[str, int, str]:
    """Creates a patient assigned to the demo therapist, who writes them one piece of advice; returns (e-mail, id,
    full name)."""
    email, name = f"reply-{uuid.uuid4().hex[:8]}@example.org", f"Rita Reply {uuid.uuid4().hex[:4]}"
    admin, headers = api_client(base, "admin@demo.clinic")
    tara, tara_headers = api_client(base, THERAPIST)
    try:
        r = admin.post("/api/v1/users", json={"email": email, "role": "patient", "password": PASSWORD,
                                              "full_name": name}, headers=headers)  # fmt: skip
        assert r.status_code == 201, r.text
        pid = r.json()["id"]
        tara_id = tara.get("/api/v1/users/me").json()["id"]
        assert admin.put(f"/api/v1/patients/{pid}/therapists/{tara_id}", headers=headers).status_code == 204
        r = tara.post(f"/api/v1/patients/{pid}/suggestions", json={"text": ADVICE}, headers=tara_headers)
        assert r.status_code == 201, r.text
    finally:
        admin.close()
        tara.close()
    return email, pid, name


def _serious(page) -> list[str]:
    return [v["id"] for v in Axe().run(page).response["violations"] if v["impact"] in ("serious", "critical")]


@pytest.mark.parametrize("width,height", [(1366, 900), (390, 844)])
def test_patient_answers_it_hurt_and_the_dashboard_shows_it_unread_live(browser, live_server, width, height):
    base = live_server.url
    email, pid, name = _patient_with_advice(base)
    with open_page(browser, base, width, height) as dashboard, open_page(browser, base, width, height) as patient:
        login(dashboard, THERAPIST)
        dashboard.wait_for_url("**/therapist")
        row = dashboard.locator(f"#patients tr[data-patient-id='{pid}']")
        expect(row).to_be_visible(timeout=LOAD_MS)
        expect(row.locator(".new-replies")).to_have_count(0)
        link = f"a[href$='/therapist/patients/{pid}#replies-h']"
        unread = dashboard.locator(f"#unread-replies {link}")
        expect(unread).to_have_count(0)

        login(patient, email, PASSWORD)
        advice = patient.locator("#advice li", has_text=ADVICE)
        expect(advice).to_be_visible(timeout=LOAD_MS)
        advice.get_by_role("button", name="It hurt").click()
        expect(advice.locator(".answered")).to_contain_text("You answered today: It hurt")
        expect(advice.get_by_role("status")).to_have_text("Sent. Your therapist will see your answer.")
        expect(advice.get_by_role("button", name="It hurt")).to_be_focused()  # the redraw keeps the keyboard's place
        shot(patient, f"reply-patient-{width}")
        assert not _serious(patient)

        # the dashboard was not reloaded: its event stream brought the reply
        expect(unread).to_have_text(name, timeout=LOAD_MS)
        item = dashboard.locator("#unread-replies li").filter(has=dashboard.locator(link))
        expect(item).to_contain_text("new")
        expect(item).to_contain_text("It hurt")
        expect(item).to_contain_text(ADVICE[:40])
        expect(row.locator(".new-replies")).to_have_text("1 new reply")
        shot(dashboard, f"reply-dashboard-{width}")
        assert not _serious(dashboard)

        unread.click()  # the therapist opens the patient's page: the reply shows as new there and is marked read
        replies = dashboard.locator("#replies li[data-reply-id]")
        expect(replies).to_have_count(1, timeout=LOAD_MS)
        expect(replies.first).to_contain_text("new")
        expect(replies.first).to_contain_text("It hurt")
        expect(patient.locator("#advice .answered .read")).to_contain_text("read by your therapist", timeout=LOAD_MS)
        dashboard.locator("#replies-h").scroll_into_view_if_needed()
        shot(dashboard, f"reply-therapist-patient-{width}")
        dashboard.go_back()
        expect(row.locator(".new-replies")).to_have_count(0, timeout=LOAD_MS)
        expect(unread).to_have_count(0)
        assert not dashboard.js_errors and not patient.js_errors, (dashboard.js_errors, patient.js_errors)


def test_a_german_patient_answers_in_german(browser, live_server):
    base = live_server.url
    email, pid, _ = _patient_with_advice(base)
    with open_page(browser, base, 390, 844) as page:
        login(page, email, PASSWORD)
        advice = page.locator("#advice li", has_text=ADVICE)
        expect(advice).to_be_visible(timeout=LOAD_MS)
        with page.expect_navigation():
            page.locator("#language").select_option("de")  # saves the patient's language and shows the page in it
        expect(advice.get_by_role("button", name="Es hat wehgetan")).to_be_visible(timeout=LOAD_MS)
        advice.get_by_role("button", name="Erledigt").click()
        expect(advice.locator(".answered")).to_contain_text("Sie haben heute geantwortet: Erledigt")
        advice.get_by_role("button", name="Senden").click()  # nothing written yet
        expect(advice.get_by_role("alert")).to_have_text("Bitte schreiben Sie zuerst ein paar Worte.")
        advice.get_by_label("Oder schreiben Sie").fill("Das Knie war steif.")
        advice.get_by_role("button", name="Senden").click()
        expect(advice.locator(".answered li")).to_have_count(2)
        expect(advice.locator(".answered li").last).to_contain_text("geantwortet: Das Knie war steif.")
        expect(advice.get_by_label("Oder schreiben Sie")).to_have_value("")
        shot(page, "reply-patient-de-390")
        assert not _serious(page)
        assert not page.js_errors, page.js_errors
