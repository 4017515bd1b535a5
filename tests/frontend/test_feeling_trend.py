"""How the sets felt in the trends (issue 23, point 4): the patient's page and the therapist's patient page plot the
pain (0-10) and effort (Borg CR10) said after each set; the therapist sets the patient's pain alert level there."""

from __future__ import annotations

import datetime as dt
from typing import Any

import httpx
import pytest
from axe_playwright_python.sync_playwright import Axe
from playwright.sync_api import expect

from tests.backend.khs_files import make_khs
from tests.frontend.conftest import THERAPIST, api_client, login, open_page, shot
from tests.frontend.test_feeling import _assign_to_tara
from tests.frontend.test_live_set import PASSWORD
from tests.frontend.test_never_silent import EXERCISE, LOAD_MS, patient_with_device

pytestmark = pytest.mark.browser
SAID = [(6, 2, 3.0), (3, 4, 5.0), (1, 6, 6.5)]  # (days ago, pain, effort)


def _patient_who_said_how_it_felt(base: str) -> tuple[str, int]:
    """Returns (e-mail, id) of a new patient of Tara's with three sets of the last week, each answered (SAID)."""
    email, pid, token = patient_with_device(base)
    _assign_to_tara(base, pid)
    now = dt.datetime.now(dt.UTC).replace(microsecond=0)
    with httpx.Client(base_url=base, timeout=60) as patient:
        login_body = patient.post("/api/v1/auth/login", json={"email": email, "password": PASSWORD}).json()
        csrf = {"X-CSRF-Token": login_body["csrf_token"]}
        for seed, (days, pain, effort) in enumerate(SAID):
            when = (now - dt.timedelta(days=days)).strftime("%Y-%m-%dT%H:%M:%SZ")
            device = {"Authorization": f"Bearer {token}", "Content-Type": "application/octet-stream"}
            r = httpx.post(f"{base}/api/v1/sessions", params={"exercise": EXERCISE}, timeout=60,
                           content=make_khs(EXERCISE, 3, seed=70 + seed, created_at=when), headers=device)  # fmt: skip
            assert r.status_code == 201, r.text
            r = patient.put(f"/api/v1/sessions/{r.json()['id']}/feeling", json={"pain": pain, "effort": effort},
                            headers=csrf)  # fmt: skip
            assert r.status_code == 200, r.text
    return email, pid


def _traces(page, figure) -> list[dict[str, Any]]:
    """Returns the Plotly traces drawn in a figure: name and y values."""
    return figure.evaluate("(f) => f.plot.data.map((t) => ({ name: t.name, y: [...t.y] }))")


def _serious(page) -> list[str]:
    return [v["id"] for v in Axe().run(page).response["violations"] if v["impact"] in ("serious", "critical")]


@pytest.mark.parametrize("width,height", [(1366, 900), (390, 844)])
def test_the_trends_show_pain_and_effort_and_the_therapist_sets_the_alert(browser, live_server, width, height):
    base = live_server.url
    email, pid = _patient_who_said_how_it_felt(base)
    with open_page(browser, base, width, height) as page:
        login(page, email, PASSWORD)
        figure = page.locator("figure.plot-figure", has_text="How it felt after your exercises")
        expect(figure.locator(".plot .main-svg").first).to_be_visible(timeout=LOAD_MS)
        assert _traces(page, figure) == [{"name": "Pain", "y": [2, 4, 6]}, {"name": "How hard", "y": [3, 5, 6.5]}]
        figure.get_by_role("button", name="Show as table").click()
        expect(figure.locator("table tbody tr")).to_have_count(3)
        expect(figure.locator("table tbody tr").last).to_contain_text("6.5")
        figure.scroll_into_view_if_needed()
        shot(page, f"feeling-trend-patient-{width}")
        assert page.evaluate("document.documentElement.scrollWidth") <= width, "the page scrolls sideways"
        assert not _serious(page)
        assert not page.js_errors, page.js_errors
    with open_page(browser, base, width, height) as page:
        login(page, THERAPIST)
        page.wait_for_url("**/therapist")
        page.goto(f"/therapist/patients/{pid}")
        figure = page.locator("figure.plot-figure", has_text="How the sets felt")
        expect(figure.locator(".plot .main-svg").first).to_be_visible(timeout=LOAD_MS)
        traces = _traces(page, figure)
        assert traces[:2] == [{"name": "pain (0–10, NRS)", "y": [2, 4, 6]},
                              {"name": "effort (Borg CR10)", "y": [3, 5, 6.5]}], traces  # fmt: skip
        alert = page.locator("#pain-alert-above")
        expect(alert).to_have_value("5")
        expect(figure).to_contain_text("pain alert above 5")
        alert.fill("12")
        page.get_by_role("button", name="Save pain alert").click()
        expect(page.locator("#pain-alert-msg")).to_have_text("Enter a whole number from 0 to 9.")
        expect(alert).to_have_attribute("aria-invalid", "true")
        alert.fill("3")
        page.get_by_role("button", name="Save pain alert").click()
        expect(page.locator("#pain-alert-msg")).to_contain_text("pain above 3 of 10")
        figure = page.locator("figure.plot-figure", has_text="How the sets felt")
        expect(figure).to_contain_text("pain alert above 3")  # the chart's line follows the saved level
        figure.scroll_into_view_if_needed()
        shot(page, f"feeling-trend-therapist-{width}")
        assert page.evaluate("document.documentElement.scrollWidth") <= width, "the page scrolls sideways"
        assert not _serious(page)
        assert not page.js_errors, page.js_errors
    tara, _ = api_client(base, THERAPIST)
    try:
        reasons = tara.get(f"/api/v1/patients/{pid}/summary").json()["attention_reasons"]
    finally:
        tara.close()
    assert any(r.startswith("Said pain 6 of 10") and r.endswith("(alert above 3)") for r in reasons), reasons


def test_a_german_patient_reads_the_pain_trend_in_german(browser, live_server):
    base = live_server.url
    email, pid = _patient_who_said_how_it_felt(base)
    with httpx.Client(base_url=base, timeout=60) as patient:
        csrf = patient.post("/api/v1/auth/login", json={"email": email, "password": PASSWORD}).json()["csrf_token"]
        r = patient.patch(f"/api/v1/patients/{pid}", json={"locale": "de"}, headers={"X-CSRF-Token": csrf})
        assert r.status_code == 200, r.text
    with open_page(browser, base, 390, 844) as page:
        login(page, email, PASSWORD)
        figure = page.locator("figure.plot-figure", has_text="Wie es sich nach Ihren Übungen anfühlte")
        expect(figure.locator(".plot .main-svg").first).to_be_visible(timeout=LOAD_MS)
        assert [t["name"] for t in _traces(page, figure)] == ["Schmerz", "Wie anstrengend"]
        figure.get_by_role("button", name="Als Tabelle zeigen").click()
        expect(figure.locator("table thead")).to_contain_text("Schmerz (0 bis 10)")
        expect(figure.locator("table tbody tr").last).to_contain_text("6,5")  # the German decimal comma
        figure.scroll_into_view_if_needed()
        shot(page, "feeling-trend-patient-de-390")
        assert not _serious(page)
        assert not page.js_errors, page.js_errors
