"""Before Start, each exercise of the plan shows how it is done (issue 23, point 3): a looping figure of one
repetition from the motion library (side view for these sagittal exercises), the library's instructions, the
therapist's note, and a badge that reads "N× this week". No camera or home computer is needed (Rose has none)."""

from __future__ import annotations

import re

import pytest
from axe_playwright_python.sync_playwright import Axe
from playwright.sync_api import TimeoutError as PlaywrightTimeout
from playwright.sync_api import expect

from tests.frontend.conftest import (
    NEW_PATIENT_PASSWORD,
    PATIENT,
    api_client,
    create_patient,
    login,
    open_page,
    plan_item,
    shot,
)

pytestmark = pytest.mark.browser
MOVES_MS = 5_000  # how long a looping figure may take to draw another frame on a loaded machine


def _moves(canvas, slug: str) -> None:
    """Asserts that the figure draws a different picture within MOVES_MS (a figure that does not move never does)."""
    first = canvas.evaluate("(c) => c.toDataURL()")
    try:
        canvas.page.wait_for_function("([c, first]) => c.toDataURL() !== first", arg=[canvas.element_handle(), first],
                                      timeout=MOVES_MS, polling=100)  # fmt: skip
    except PlaywrightTimeout:
        pytest.fail(f"the figure of {slug} does not move")


@pytest.mark.parametrize("width,height", [(1366, 900), (768, 1024), (390, 844)])
def test_each_exercise_shows_a_moving_figure_its_instructions_and_the_week_badge(browser, live_server, width, height):
    with open_page(browser, live_server.url, width, height) as page:
        client, _ = api_client(live_server.url, PATIENT)
        try:
            library = {e["slug"]: e for e in client.get("/api/v1/exercises?limit=200").json()["items"]}
        finally:
            client.close()
        login(page, PATIENT)
        page.wait_for_url("**/patient")
        items = page.locator("#plan li[data-exercise]")
        expect(items.first).to_be_visible()
        assert items.count() == 2
        for i in range(items.count()):
            li = items.nth(i)
            slug = li.get_attribute("data-exercise")
            assert slug is not None
            canvas = li.locator("canvas.demo-figure")
            expect(canvas).to_have_attribute("data-view", "side")
            assert int(canvas.get_attribute("data-frames") or 0) >= 30
            expect(li.locator(".demo-instructions")).to_have_text(library[slug]["instructions"])
            expect(li.locator(".week-label")).to_have_text("this week")
            expect(li.locator(".tick")).to_have_text(re.compile(r"^(\d+×|✓)$"))
            expect(canvas).to_have_attribute("aria-label", re.compile(f"^How to do {library[slug]['name']}"))
            _moves(canvas, slug)
        shot(page, f"demonstration-{width}")
        bad = [v["id"] for v in Axe().run(page).response["violations"] if v["impact"] in ("serious", "critical")]
        assert not bad, bad
        assert not page.js_errors, page.js_errors


LANGUAGES = [
    ("de", "Stimme an", "So geht es", "Von der Seite gesehen"),
    ("es", "Voz activada", "Cómo se hace", "Visto de lado"),
    ("fr", "Voix activée", "Comment faire", "Vu de côté"),
]


@pytest.mark.parametrize(("locale", "voice", "how", "view"), LANGUAGES)
def test_the_voice_control_and_the_demonstration_speak_the_patients_language(
    browser, live_server, locale, voice, how, view
):
    from tests.frontend.test_never_silent import AgentLink, patient_with_device

    email, pid, token = patient_with_device(live_server.url)
    AgentLink(live_server.url, token).close()
    patient, headers = api_client(live_server.url, "admin@demo.clinic")
    try:
        assert patient.patch(f"/api/v1/patients/{pid}", json={"locale": locale}, headers=headers).status_code == 200
    finally:
        patient.close()
    with open_page(browser, live_server.url, 768, 1024) as page:
        login(page, email, NEW_PATIENT_PASSWORD)
        expect(page.locator("#voice-toggle")).to_have_text(voice, timeout=30_000)
        expect(page.locator(".demo-h")).to_have_text(how, timeout=30_000)
        expect(page.locator(".demo-view")).to_have_text(view, timeout=30_000)
        assert page.evaluate("I18n.tag") == locale
        shot(page, f"patient-{locale}")


# The UI-PRMD movements of the library and the view each needs (side: sagittal plane, else front).
UI_PRMD_VIEWS = {
    "deep_squat": "side", "hurdle_step": "side", "inline_lunge": "side", "side_lunge": "front",
    "standing_active_straight_leg_raise": "side", "standing_shoulder_abduction": "front",
    "standing_shoulder_extension": "side", "standing_shoulder_rotation": "front", "standing_shoulder_scaption": "front",
}  # fmt: skip


def _patient_with_uiprmd_plan(base: str) -> str:
    """Creates a patient whose plan holds every UI-PRMD movement except sit to stand; returns the e-mail."""
    items = [plan_item(slug, 8, sets=1) for slug in UI_PRMD_VIEWS]
    return create_patient(base, "uiprmd", "Una Prmd", items=items, plan={"title": "UI-PRMD"}).email


@pytest.mark.parametrize("width,height", [(1366, 900), (768, 1024), (390, 844)])
def test_every_uiprmd_movement_shows_a_moving_figure_in_the_view_it_needs(browser, live_server, width, height):
    email = _patient_with_uiprmd_plan(live_server.url)
    with open_page(browser, live_server.url, width, height) as page:
        login(page, email, NEW_PATIENT_PASSWORD)
        page.wait_for_url("**/patient")
        items = page.locator("#plan li[data-exercise]")
        expect(items.first).to_be_visible()
        assert items.count() == len(UI_PRMD_VIEWS)
        for i in range(items.count()):
            li = items.nth(i)
            slug = li.get_attribute("data-exercise")
            assert slug is not None
            canvas = li.locator("canvas.demo-figure")
            expect(canvas).to_have_attribute("data-view", UI_PRMD_VIEWS[slug])
            assert int(canvas.get_attribute("data-frames") or 0) >= 30, slug
            _moves(canvas, slug)
        shot(page, f"demonstration-uiprmd-{width}")
        assert not page.js_errors, page.js_errors
    with open_page(browser, live_server.url, width, height, reduced_motion="reduce") as page:  # still, at the peak
        login(page, email, NEW_PATIENT_PASSWORD)
        page.wait_for_url("**/patient")
        canvases = page.locator("#plan li[data-exercise] canvas.demo-figure[data-frames]")
        expect(canvases).to_have_count(len(UI_PRMD_VIEWS))
        shot(page, f"demonstration-uiprmd-peak-{width}")
