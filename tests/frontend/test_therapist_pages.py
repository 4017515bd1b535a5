"""The therapist's pages as a therapist uses them (issue 23, point 8), in Chromium: the dashboard's table fits at
1366 px and its reasons are never cut at 390 px, the plan editor refuses an exercise twice with a message, "Sent and
decided" comes in pages with links named by the session's date, and the session page's parameter boxes scroll with
the keyboard."""

from __future__ import annotations

import re

import pytest
from axe_playwright_python.sync_playwright import Axe
from playwright.sync_api import expect

from tests.frontend.conftest import THERAPIST, login, newest_session_id, shot

pytestmark = pytest.mark.browser

CUT_REASONS = """() => {
  const width = document.documentElement.clientWidth;
  return [...document.querySelectorAll('#patients .reasons, #patients .reasons li')]
    .filter((e) => e.getBoundingClientRect().right > width + 0.5).map((e) => e.textContent.slice(0, 40));
}"""


def _dashboard(page, width: int) -> None:
    page.set_viewport_size({"width": width, "height": 900})
    login(page, THERAPIST)
    page.wait_for_url("**/therapist")
    page.locator("#patients tbody tr[data-patient-id]").first.wait_for()


def test_dashboard_table_is_not_cut_at_1366(page, live_server):
    _dashboard(page, 1366)
    wrap = page.locator("#patients").locator("xpath=..")
    scroll, client = wrap.evaluate("(w) => [w.scrollWidth, w.clientWidth]")
    assert scroll <= client, f"the patients table is cut: {scroll} px wide in a {client} px box"
    box = page.locator("#patients thead th").last.bounding_box()
    assert box["x"] + box["width"] <= 1366, box
    assert not page.js_errors, page.js_errors


def test_dashboard_reasons_are_not_cut_at_390(page, live_server):
    _dashboard(page, 390)
    shot(page, "therapist_dashboard_cards_390")
    assert page.evaluate(CUT_REASONS) == []
    assert page.locator("#patients td.attention").first.evaluate("(td) => getComputedStyle(td, '::before').content")
    violations = [v for v in Axe().run(page).response["violations"] if v["impact"] in ("serious", "critical")]
    assert not violations, [(v["id"], [n["target"] for n in v["nodes"][:3]]) for v in violations]


def test_plan_editor_refuses_the_same_exercise_twice_with_a_message(page, live_server):
    login(page, THERAPIST)
    page.wait_for_url("**/therapist")
    page.goto(f"/therapist/patients/{live_server.patient_id}")
    page.locator("#plan-items li, #plan-edit").first.wait_for()
    page.click("#plan-edit")
    first = page.locator("#plan-rows .plan-row select").first.input_value()
    page.click("#plan-add")
    last = page.locator("#plan-rows .plan-row").last
    last.locator("select").select_option(first)
    last.locator('input[name="sets"]').fill("1")
    last.locator('input[name="repetitions"]').fill("5")
    last.locator('input[name="frequency_per_week"]').fill("2")
    page.click("#plan-save")
    error = last.locator('.field-error[id$="-exercise-err"]')
    expect(error).to_contain_text("is already exercise 1 of this plan")
    expect(last.locator("select")).to_have_attribute("aria-invalid", "true")
    expect(page.locator("#plan-form")).to_be_visible()  # nothing was sent
    assert not page.js_errors, page.js_errors


def test_sent_and_decided_is_paged_and_links_name_the_sessions_date(page, live_server):
    login(page, THERAPIST)
    page.wait_for_url("**/therapist")
    page.goto(f"/therapist/patients/{live_server.patient_id}")
    decided = page.locator("#decided li")
    decided.first.wait_for()
    assert decided.count() <= 5
    links = page.locator("#decided a.session-link, #pending a.session-link")
    links.first.wait_for()
    for text in links.all_inner_texts():
        assert text.startswith("session of "), text
    if page.locator("#decided-pager").is_visible():
        before = decided.all_inner_texts()
        page.click("#decided-next")
        expect(page.locator("#decided-info")).to_contain_text("page 2 of")
        assert decided.all_inner_texts() != before
    assert not page.js_errors, page.js_errors


def test_processing_boxes_scroll_with_the_keyboard(page, live_server):
    login(page, THERAPIST)
    page.wait_for_url("**/therapist")
    session_id = newest_session_id(live_server.url, THERAPIST, live_server.patient_id)
    page.goto(f"/therapist/sessions/{session_id}")
    page.locator("#processing summary").click()  # the section opens on demand
    boxes = page.locator("pre.params")
    boxes.first.wait_for()
    for k in range(boxes.count()):
        box = boxes.nth(k)
        assert box.get_attribute("tabindex") == "0" and box.get_attribute("aria-label"), box.get_attribute("class")
    longest = max(range(boxes.count()), key=lambda k: boxes.nth(k).evaluate("(b) => b.textContent.length"))
    box = boxes.nth(longest)  # the file's recorded parameters may be a short one
    # make it scroll whatever the parameters' length (a test session's may be three lines)
    box.evaluate("(b) => { b.style.maxHeight = '4rem'; b.textContent += '\\n'.repeat(40); }")
    box.focus()
    page.keyboard.press("PageDown")
    page.wait_for_function("(b) => b.scrollTop > 0", arg=box.element_handle())  # keyboard scrolling is animated
    found = Axe().run(page, options={"runOnly": ["scrollable-region-focusable"]}).response["violations"]
    assert not found, found


def test_therapist_sets_the_patients_language(page, live_server):
    login(page, THERAPIST)
    page.wait_for_url("**/therapist")
    page.goto(f"/therapist/patients/{live_server.patient_id}")
    select = page.locator("#patient-locale")
    expect(select).to_have_value("")
    try:
        select.select_option("fr")
        expect(page.locator("#patient-locale-saved")).to_contain_text("Saved")
        found = page.evaluate(
            f"async () => (await (await fetch(Coach.url('/api/v1/patients/{live_server.patient_id}'))).json()).locale"
        )
        assert found == "fr"
    finally:
        select.select_option("")
        expect(page.locator("#patient-locale-saved")).to_contain_text("browser decides")
    assert not page.js_errors, page.js_errors


def test_replay_shows_raw_and_filtered_through_two_plain_checkboxes(page, live_server):
    login(page, THERAPIST)
    page.wait_for_url("**/therapist")
    session_id = newest_session_id(live_server.url, THERAPIST, live_server.patient_id)
    page.goto(f"/therapist/sessions/{session_id}/replay")
    raw, filtered = page.get_by_label("Raw skeleton"), page.get_by_label("Filtered skeleton")
    expect(raw).to_be_checked()
    expect(filtered).to_be_checked()
    recording = page.locator("#viewer").get_attribute("src")
    raw.uncheck()  # a worker builds the filtered skeleton alone: the page says so and keeps playing both meanwhile
    expect(page.locator("#replay-state")).to_contain_text("The 3D replay of the filtered skeleton alone is being")
    expect(page.locator("#viewer")).to_have_attribute("src", recording)
    expect(page.locator("#viewer")).to_have_attribute("src", re.compile(r"replay%3Flayer%3Dfiltered$"),
                                                      timeout=60_000)  # fmt: skip
    expect(page.locator("#replay-state")).to_be_hidden()
    page.frame_locator("#viewer").locator("canvas").first.wait_for(state="visible", timeout=30_000)
    filtered.click()  # the last one shown stays shown
    expect(filtered).to_be_checked()
    expect(page.locator("#layers-note")).to_contain_text("At least one skeleton")
    raw.check()
    expect(page.locator("#viewer")).to_have_attribute("src", re.compile(r"replay$"))
    shot(page, "replay_checkboxes")
    violations = [v for v in Axe().run(page).response["violations"] if v["impact"] in ("serious", "critical")]
    assert not violations, [(v["id"], [n["target"] for n in v["nodes"][:3]]) for v in violations]
    assert not page.js_errors, page.js_errors
