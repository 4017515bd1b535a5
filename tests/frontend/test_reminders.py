"""Reminders (issue 23, point 6): the patient's page shows today's next reminder, at its time in the patient's time
zone and in the patient's language; the therapist sets reminder times in the plan editor."""

from __future__ import annotations

import time

import pytest
from axe_playwright_python.sync_playwright import Axe
from playwright.sync_api import expect

from tests.frontend.conftest import (
    NEW_PATIENT_PASSWORD,
    THERAPIST,
    api_client,
    create_patient,
    login,
    open_page,
    plan_item,
    shot,
)
from tests.frontend.test_feeling import _assign_to_tara
from tests.frontend.test_never_silent import LOAD_MS

pytestmark = pytest.mark.browser
PASSWORD = NEW_PATIENT_PASSWORD


def _zone_where_it_is_ten() -> str:
    """Returns a fixed-offset IANA zone (Etc/GMT±N) in which it is now between 10:00 and 10:59: the reminder at
    11:00 is still to come today, whatever the hour the test runs."""
    offset = 10 - time.gmtime().tm_hour  # hours east of UTC
    offset = offset + 24 if offset < -12 else offset
    return "Etc/GMT" + ("+0" if offset == 0 else f"{-offset:+d}")  # POSIX sign: Etc/GMT-2 is UTC+2


def _patient(base: str, **settings) -> tuple[str, int]:
    start = time.strftime("%Y-%m-%d", time.gmtime(time.time() - 86400))
    plan = {"title": "Arms", "start_date": start, "reminder_times": ["18:00", "11:00"]}
    new = create_patient(base, "remind", "Rita Reminder", items=[plan_item("elbow_flexion", 8)], plan=plan,
                         settings=settings)  # fmt: skip
    return new.email, new.id


@pytest.mark.parametrize("width,height", [(1366, 900), (390, 844)])
def test_the_patient_page_shows_todays_next_reminder_in_their_language(browser, live_server, width, height):
    email, _ = _patient(live_server.url, locale="de", time_zone=_zone_where_it_is_ten())
    with open_page(browser, live_server.url, width, height) as page:
        login(page, email, PASSWORD)
        reminder = page.locator("#reminder")
        expect(reminder).to_have_text("Erinnerung: Ihre Übungen um 11:00", timeout=LOAD_MS)
        expect(page.locator("#plan li[data-exercise]")).to_have_count(1)
        box = reminder.bounding_box()
        assert box is not None and box["x"] >= 0 and box["x"] + box["width"] <= width, box
        shot(page, f"reminder-de-{width}")
        bad = [v["id"] for v in Axe().run(page).response["violations"] if v["impact"] in ("serious", "critical")]
        assert not bad, bad
        assert not page.js_errors, page.js_errors


def test_the_therapist_sets_reminder_times_in_the_plan_editor(browser, live_server):
    base = live_server.url
    email, pid = _patient(base, time_zone="Europe/Berlin")
    _assign_to_tara(base, pid)
    with open_page(browser, base, 1366, 900) as page:
        login(page, THERAPIST)
        page.wait_for_url("**/therapist")
        page.goto(f"/therapist/patients/{pid}")
        expect(page.locator("#plan-reminders-shown")).to_have_text("Reminders: 11:00, 18:00 (Europe/Berlin)",
                                                                   timeout=LOAD_MS)  # fmt: skip
        zone_field = page.locator("#patient-tz")
        expect(zone_field).to_have_value("Europe/Berlin")
        zone_field.fill("Mars/Olympus")
        zone_field.dispatch_event("change")
        expect(page.locator("#patient-tz-saved")).to_contain_text(
            "Not saved: body.time_zone: Value error, time zone 'Mars/Olympus' is not an IANA time zone name"
        )
        zone_field.fill("Europe/Madrid")
        zone_field.dispatch_event("change")
        expect(page.locator("#patient-tz-saved")).to_have_text("Saved: reminders follow Europe/Madrid.")
        expect(page.locator("#plan-reminders-shown")).to_have_text("Reminders: 11:00, 18:00 (Europe/Madrid)")
        page.locator("#plan-edit").click()
        field = page.locator("#plan-reminders")
        expect(field).to_have_value("11:00, 18:00")
        field.fill("9:15, 25:00")
        page.locator("#plan-save").click()
        expect(page.locator("#plan-reminders-err")).to_contain_text("“25:00” is not a time like 09:00")
        expect(field).to_have_attribute("aria-invalid", "true")
        field.fill("9:15, 20:45")
        page.locator("#plan-save").click()
        expect(page.locator("#plan-reminders-shown")).to_have_text("Reminders: 09:15, 20:45 (Europe/Madrid)")
        shot(page, "reminder-therapist-1366")
    client, _ = api_client(base, "admin@demo.clinic")
    try:
        plans = client.get(f"/api/v1/patients/{pid}/plans").json()["items"]
        assert plans[0]["reminder_times"] == ["09:15", "20:45"]
    finally:
        client.close()


def _unsubscribe_token(live_server, pid: int) -> str:
    """Claims a reminder e-mail of the patient's plan in the server's database, as the reminder loop does before
    sending one, and returns the token its unsubscribe link carries."""
    import datetime as dt

    from sqlalchemy import create_engine, select
    from sqlalchemy.orm import Session

    from backend.plans.models import Plan
    from backend.reminders.service import DueReminder, claim

    engine = create_engine(live_server.database_url)
    try:
        with Session(engine, expire_on_commit=False) as db:
            plan_id = db.scalar(select(Plan.id).where(Plan.patient_id == pid))
            assert plan_id is not None
            now = dt.datetime.now(dt.UTC)
            claimed = claim(db_session=db, reminder=DueReminder(plan_id, pid, now.date(), "11:00", now))
            assert claimed is not None
            return claimed[1]
    finally:
        engine.dispose()


@pytest.mark.parametrize("width,height", [(1366, 900), (390, 844)])
def test_the_unsubscribe_page_works_without_login(browser, live_server, width, height):
    email, pid = _patient(live_server.url, locale="fr")
    token = _unsubscribe_token(live_server, pid)
    with open_page(browser, live_server.url, width, height) as page:  # no login
        page.goto(f"/unsubscribe/{token}")
        expect(page.locator("h1")).to_have_text("Arrêter les rappels par e-mail\u202f?")
        shot(page, f"unsubscribe-fr-{width}")
        bad = [v["id"] for v in Axe().run(page).response["violations"] if v["impact"] in ("serious", "critical")]
        assert not bad, bad
        page.get_by_role("button", name="Arrêter les rappels par e-mail").click()
        expect(page.locator("h1")).to_have_text("Plus de rappels par e-mail")
        shot(page, f"unsubscribed-fr-{width}")
        bad = [v["id"] for v in Axe().run(page).response["violations"] if v["impact"] in ("serious", "critical")]
        assert not bad, bad
        assert not page.js_errors, page.js_errors
    admin, _ = api_client(live_server.url, "admin@demo.clinic")
    try:
        assert admin.get(f"/api/v1/patients/{pid}").json()["reminder_emails"] is False
    finally:
        admin.close()
