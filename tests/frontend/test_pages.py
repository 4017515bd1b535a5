"""The pages end to end: the real server and a real browser (headless Chromium)."""

from __future__ import annotations

import re

import httpx
import pytest
from playwright.sync_api import expect

from backend.demo import DEMO_PASSWORD
from tests.frontend.conftest import PATIENT, THERAPIST, login, shot

pytestmark = pytest.mark.browser


def test_bad_password_shows_an_error_and_stays_on_login(page):
    login(page, THERAPIST, "wrong password")
    error = page.locator("#login-error")
    error.wait_for(state="visible")
    assert "not right" in error.inner_text()
    assert page.url.endswith("/")
    shot(page, "login_error")


def test_therapist_sees_patients_sorted_by_attention(page, live_server):
    login(page, THERAPIST)
    page.wait_for_url("**/therapist")
    rows = page.locator("#patients tbody tr[data-patient-id]")
    rows.first.wait_for()
    expect(rows.filter(has_text="Rose Miller")).to_have_count(1)
    assert rows.count() >= 3, rows.count()  # the demo's three, and any a test run has added to this therapist
    scores = page.eval_on_selector_all(
        "#patients tbody tr[data-patient-id]", "trs => trs.map(tr => Number(tr.dataset.attentionScore))"
    )
    assert scores == sorted(scores, reverse=True) and scores[0] > 0, scores  # who needs attention first
    rose = rows.filter(has_text="Rose Miller")
    assert "to review" in rose.inner_text()  # her pending suggestions are one of the reasons shown
    shot(page, "therapist_dashboard")
    assert not page.js_errors


def test_therapist_opens_patient_sees_chart_and_approves_a_suggestion(page, live_server):
    login(page, THERAPIST)
    page.wait_for_url("**/therapist")
    page.click("text=Rose Miller")
    page.wait_for_url(re.compile(rf"/therapist/patients/{live_server.patient_id}$"))
    points = page.locator("#progress .js-plotly-plot .scatterlayer path.point")  # Plotly's markers
    points.first.wait_for()
    assert points.count() >= 8
    reps = page.locator("#progress figure", has_text="Sit to stand: repetitions vs prescribed")
    assert "prescribed 2 × 10" in reps.locator(".legend").text_content()  # the target line, named in the legend
    reps.get_by_role("button", name="Show as table").click()
    expect(reps.locator("table tbody tr")).to_have_count(4)  # the same data, readable as a table
    expect(reps.locator("table thead")).to_contain_text("Prescribed")
    expect(page.locator("#sessions tbody tr[data-session-id]")).to_have_count(8)
    pending = page.locator("#pending li[data-suggestion-id]")
    pending.first.wait_for()
    first_id = int(pending.first.get_attribute("data-suggestion-id"))
    assert first_id in live_server.pending_ids
    text = pending.first.inner_text()
    assert re.search(r"On \w+ you did \d+ of the 10 (sit-to-stands|seated knee extensions) in your plan", text), text
    assert re.search(r"Because the number of repetitions \(\d+\) was below the 10 prescribed\.", text), text
    assert "fewer_reps" not in text and "<" not in text  # a sentence, never a rule code
    shot(page, "therapist_patient")
    pending.first.get_by_role("button", name="Approve").click()
    expect(page.locator(f'#pending li[data-suggestion-id="{first_id}"] .note')).to_contain_text("Approved")
    cookies = {c["name"]: c["value"] for c in page.context.cookies()}
    r = httpx.get(f"{live_server.url}/api/v1/patients/{live_server.patient_id}/suggestions",
                  params={"status": "approved"}, cookies=cookies)  # fmt: skip
    assert first_id in [s["id"] for s in r.json()["items"]]
    assert not page.js_errors


def test_patient_sees_latest_session_in_words_and_approved_advice(page, live_server):
    login(page, PATIENT)
    page.wait_for_url("**/patient")
    sentence = page.locator("#last-sentence")
    sentence.wait_for()
    assert "You did 9 of 10 seated knee extensions" in sentence.inner_text()
    assert "well done" in sentence.inner_text()
    expect(page.locator("#advice")).to_contain_text(live_server.approved_text)
    page.locator("#charts .js-plotly-plot .scatterlayer path.point").first.wait_for()
    assert page.locator("#charts .modebar").count() == 0  # the patient's chart: no mode bar
    assert page.locator("#greeting").inner_text().endswith("Rose!")
    shot(page, "patient")
    assert not page.js_errors


def test_patient_opening_a_therapist_page_gets_403(page, live_server):
    login(page, PATIENT)
    page.wait_for_url("**/patient")
    response = page.goto(f"/therapist/patients/{live_server.patient_id}")
    assert response.status == 403
    assert "for therapists" in page.locator("#forbidden").inner_text()
    shot(page, "forbidden")


def test_not_logged_in_goes_to_login_page(page):
    page.goto("/therapist")
    assert re.search(r"/\?next=%2Ftherapist$", page.url), page.url
    page.locator("#login-form").wait_for()


OFF_SITE = ["/\\evil.example/", "/%09/evil.example/", "%2F%5Cevil.example%2F", "//evil.example/"]


@pytest.mark.parametrize("next_", OFF_SITE)
def test_login_never_follows_next_off_the_site(page, live_server, next_):
    page.goto(f"/?next={next_}")
    page.fill("#email", THERAPIST)
    page.fill("#password", DEMO_PASSWORD)
    page.click("#login-submit")
    page.wait_for_url(f"{live_server.url}/therapist")


@pytest.mark.parametrize(("email", "path"), [(None, "/"), (PATIENT, "/patient"), (THERAPIST, "/therapist")])
def test_a_page_asks_the_server_for_nothing_it_lacks(page, live_server, email, path):
    """The browser asks for the page's icon too: every page names its own (a missing /favicon.ico was a 404 and an
    error in the browser's console on every page)."""
    failed: list[str] = []
    page.on("response", lambda r: failed.append(f"{r.status} {r.url}") if r.status >= 400 else None)
    if email is not None:
        login(page, email)
        page.wait_for_url(f"**{path}")
    else:
        page.goto(path)
    with page.expect_response(lambda r: "favicon" in r.url) as icon:
        page.reload()
    assert icon.value.status == 200 and icon.value.url.endswith("/static/favicon.svg"), icon.value.url
    page.wait_for_load_state("networkidle")
    assert failed == []
