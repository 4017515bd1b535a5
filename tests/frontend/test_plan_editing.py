"""The plan card of the therapist's patient page: edit the running plan, write a new one, past plans; the patient
sees the new plan, its note and today's sets against it. Uses Ines (Tara's patient), so Rose's plan, which the
other browser tests read, stays as seeded."""

from __future__ import annotations

import datetime as dt
import json
import re

import pytest
from playwright.sync_api import TimeoutError as PlaywrightTimeout
from playwright.sync_api import expect

from tests.frontend.conftest import THERAPIST, login, open_page, shot, upload_session

pytestmark = pytest.mark.browser

INES = "ines@demo.clinic"  # assigned to Tara; seeded plan: sit_to_stand and seated_knee_extension, 2 x 10, 3 per week
NOTE = "Rest a minute between the two sets."


@pytest.fixture(scope="module")
def ines_id(live_server) -> int:
    """Ines's id, after she uploaded one sit-to-stand set of 6 today."""
    when = (dt.datetime.now(dt.UTC) - dt.timedelta(minutes=2)).strftime("%Y-%m-%dT%H:%M:%SZ")
    return upload_session(live_server.url, INES, "sit_to_stand", 6, seed=40, created_at=when)["patient_id"]


FITS = "() => document.documentElement.scrollWidth <= document.documentElement.clientWidth"


def _fits(page, width: int) -> None:
    """Resizes the window; fails unless the page stops scrolling sideways within 3 s (charts re-layout first)."""
    page.set_viewport_size({"width": width, "height": 900})
    try:
        page.wait_for_function(FITS, timeout=3000)
    except PlaywrightTimeout:
        scroll = page.evaluate("document.documentElement.scrollWidth")
        pytest.fail(f"{page.url} scrolls sideways at {width} px: {scroll} > {width}")


def _open_patient(page, patient_id: int) -> None:
    login(page, THERAPIST)
    page.wait_for_url("**/therapist")
    page.goto(f"/therapist/patients/{patient_id}")
    page.locator("#plan-items li").first.wait_for()


def test_therapist_edits_the_plan_and_the_patient_sees_it(page, browser, live_server, ines_id):
    _open_patient(page, ines_id)
    expect(page.locator("#plan-items")).to_contain_text("Sit to stand: 2 × 10, 3 days a week")
    page.click("#plan-edit")
    rows = page.locator("#plan-rows .plan-row")
    expect(rows).to_have_count(2)
    first = rows.nth(0)
    reps, rom = first.locator('input[name="repetitions"]'), first.locator('input[name="target_rom_deg"]')

    reps.fill("")
    rom.fill("200")
    page.click("#plan-save")  # client checks: the problem in words next to each field, nothing sent
    expect(first.locator(f"#{reps.get_attribute('id')}-err")).to_have_text(
        "Please enter the repetitions (a number from 1 to 1,000)."  # numbers as the page's locale writes them
    )
    expect(first.locator(f"#{rom.get_attribute('id')}-err")).to_have_text("Target range (°) must be between 1 and 180.")
    expect(reps).to_have_attribute("aria-invalid", "true")
    expect(reps).to_be_focused()
    for width in (1366, 390):
        _fits(page, width)
        page.locator("#plan-card").screenshot(path=_shot_path(f"plan_form_errors_{width}"))
    page.set_viewport_size({"width": 1280, "height": 900})

    reps.fill("12")
    rom.fill("90")
    page.click("#plan-add")  # add a row, then take it away again
    expect(rows).to_have_count(3)
    rows.nth(2).locator("select").select_option("squat")
    rows.nth(2).get_by_role("button", name="Remove exercise 3").click()
    expect(rows).to_have_count(2)
    page.fill("#plan-notes", NOTE)
    page.click("#plan-save")
    expect(page.locator("#plan-saved")).to_have_text("Plan saved — the patient sees it now.")
    expect(page.locator("#plan-form")).to_be_hidden()
    expect(page.locator("#plan-items")).to_contain_text("Sit to stand: 2 × 12, 3 days a week, target 90°")
    expect(page.locator("#plan-items")).to_contain_text("Seated knee extension: 2 × 10, 3 days a week")
    expect(page.locator("#plan-note-shown")).to_contain_text(NOTE)
    for width in (1366, 390):
        _fits(page, width)
        page.locator("#plan-card").screenshot(path=_shot_path(f"plan_card_{width}"))
    assert not page.js_errors, page.js_errors

    with open_page(browser, live_server.url, 1366, 900) as ines:
        login(ines, INES)
        ines.wait_for_url("**/patient")
        sit = ines.locator('#plan li[data-exercise="sit_to_stand"]')
        expect(sit).to_contain_text("2 sets of 12, 3 times a week, moving through about 90 degrees")
        expect(sit.locator(".today")).to_contain_text("set 1 of 2: 6 of 12")
        expect(sit.locator(".today")).to_contain_text("set 2 of 2: 0 of 12")
        knee = ines.locator('#plan li[data-exercise="seated_knee_extension"]')
        expect(knee.locator(".today")).to_contain_text("set 1 of 2: 0 of 10")
        expect(ines.locator("#plan-note")).to_have_text(f"From your therapist: {NOTE}")
        for width in (1366, 390):
            _fits(ines, width)
            shot(ines, f"patient_plan_{width}")


def test_api_validation_detail_is_shown_next_to_its_field(page, ines_id):
    _open_patient(page, ines_id)
    page.click("#plan-edit")
    detail = "body.items.1.sets: Input should be less than or equal to 100"
    body = json.dumps({"error": "ValidationError", "detail": detail})
    answer = {"status": 422, "content_type": "application/json", "body": body}
    page.route(re.compile(r".*/api/v1/plans/\d+$"), lambda route: route.fulfill(**answer))
    page.click("#plan-save")
    second = page.locator("#plan-rows .plan-row").nth(1)
    sets = second.locator('input[name="sets"]')
    expect(second.locator(f"#{sets.get_attribute('id')}-err")).to_have_text(
        "Sets: Input should be less than or equal to 100."
    )
    expect(sets).to_have_attribute("aria-invalid", "true")
    expect(page.locator("#plan-msg")).to_contain_text(f"Please check it and try again. ({detail})")
    assert not page.js_errors, page.js_errors


def test_new_plan_replaces_the_running_one_and_the_old_one_is_history(page, ines_id):
    _open_patient(page, ines_id)
    page.click("#plan-new")
    expect(page.locator("#plan-form-h")).to_contain_text("New plan")
    expect(page.locator("#plan-rows .plan-row")).to_have_count(2)  # starts from the running plan's exercises
    page.fill("#plan-title", "Weeks 5 to 8")
    page.locator("#plan-rows .plan-row").nth(1).locator('input[name="sets"]').fill("3")
    page.click("#plan-save")
    expect(page.locator("#plan-saved")).to_have_text("New plan saved — the patient sees it now.")
    expect(page.locator("#plan-title-shown")).to_contain_text("Weeks 5 to 8")
    expect(page.locator("#plan-items")).to_contain_text("Seated knee extension: 3 × 10")
    old = page.locator("#plan-history li[data-plan-id]").first
    expect(old).to_contain_text("Home programme")
    expect(old).to_contain_text("Prescribed by Tara Therapist")
    yesterday = dt.date.today() - dt.timedelta(days=1)
    expect(old).to_contain_text(f"{yesterday.day} {yesterday:%b} {yesterday.year}")  # it ended the day before
    page.locator("#plan-card").screenshot(path=_shot_path("plan_history_1366"))
    assert not page.js_errors, page.js_errors


def _shot_path(name: str) -> str:
    from tests.frontend.conftest import SHOTS

    SHOTS.mkdir(parents=True, exist_ok=True)
    return str(SHOTS / f"{name}.png")
