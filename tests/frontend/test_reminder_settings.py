"""Reminder settings on the patient's page (issue 23, point 6): the patient chooses their time zone (the browser's own
offered first) and turns reminder e-mails off; the reminder shown follows the new zone at once, messages are in the
patient's language, and the choice is kept."""

from __future__ import annotations

import time

import pytest
from axe_playwright_python.sync_playwright import Axe
from playwright.sync_api import expect

from tests.frontend.conftest import api_client, login, open_page, shot
from tests.frontend.test_never_silent import LOAD_MS
from tests.frontend.test_reminders import PASSWORD, _patient

pytestmark = pytest.mark.browser
DEVICE_ZONE = "America/Sao_Paulo"  # the browser's own zone (the context's timezone_id)


def _zone_where_it_is(hour: int) -> str:
    """Returns a fixed-offset IANA zone (Etc/GMT±N) in which it is now between hour:00 and hour:59."""
    offset = hour - time.gmtime().tm_hour  # hours east of UTC
    offset = offset + 24 if offset < -12 else offset - 24 if offset > 14 else offset
    return "Etc/GMT" + ("+0" if offset == 0 else f"{-offset:+d}")  # POSIX sign: Etc/GMT-2 is UTC+2


def _serious(page) -> list[str]:
    return [v["id"] for v in Axe().run(page).response["violations"] if v["impact"] in ("serious", "critical")]


@pytest.mark.parametrize("width,height", [(1366, 900), (390, 844)])
def test_the_patient_changes_their_time_zone_and_turns_reminder_emails_off(browser, live_server, width, height):
    ten, noon = _zone_where_it_is(10), _zone_where_it_is(12)
    email, pid = _patient(live_server.url, locale="es", time_zone=ten)  # reminders at 11:00 and 18:00
    with open_page(browser, live_server.url, width, height, timezone_id=DEVICE_ZONE) as page:
        login(page, email, PASSWORD)
        reminder = page.locator("#reminder")
        expect(reminder).to_have_text("Recordatorio: sus ejercicios a las 11:00", timeout=LOAD_MS)
        zone = page.locator("#remind-zone")
        expect(zone).to_have_value(ten)
        first = zone.locator("option").first
        expect(first).to_have_attribute("value", DEVICE_ZONE)
        expect(first).to_have_text("America/Sao Paulo (este dispositivo)")
        switch = page.get_by_role("switch", name="Enviarme los recordatorios por correo electrónico")
        expect(switch).to_be_checked()
        for target in (zone, page.locator("label.remind-emails")):
            box = target.bounding_box()
            assert box is not None and box["height"] >= 44 and box["x"] + box["width"] <= width, box
        page.locator("#reminder-settings").scroll_into_view_if_needed()
        shot(page, f"reminder-settings-es-{width}")
        assert not _serious(page)

        zone.select_option(noon)  # now 12:xx there: the 11:00 reminder has passed, the next is 18:00
        status = page.locator("#remind-saved")
        expect(status).to_have_text(f"Guardado. Sus recordatorios siguen ahora el reloj de {noon}.")
        expect(reminder).to_have_text("Recordatorio: sus ejercicios a las 18:00")

        switch.click()
        expect(status).to_have_text("Guardado. Ya no recibirá recordatorios por correo electrónico.")
        expect(switch).not_to_be_checked()
        page.locator("#reminder-settings").scroll_into_view_if_needed()
        shot(page, f"reminder-settings-saved-es-{width}")
        assert not _serious(page)

        page.reload()  # the page comes back with what was saved
        expect(page.locator("#remind-zone")).to_have_value(noon, timeout=LOAD_MS)
        expect(switch).not_to_be_checked()
        expect(reminder).to_have_text("Recordatorio: sus ejercicios a las 18:00", timeout=LOAD_MS)
        assert not page.js_errors, page.js_errors
    admin, _ = api_client(live_server.url, "admin@demo.clinic")
    try:
        saved = admin.get(f"/api/v1/patients/{pid}").json()
        assert (saved["time_zone"], saved["reminder_emails"]) == (noon, False), saved
    finally:
        admin.close()


def test_a_setting_that_is_not_saved_is_said_and_undone(browser, live_server):
    ten = _zone_where_it_is(10)
    email, _ = _patient(live_server.url, locale="de", time_zone=ten)
    with open_page(browser, live_server.url, 1366, 900, timezone_id=DEVICE_ZONE) as page:
        login(page, email, PASSWORD)
        expect(page.locator("#reminder")).to_have_text("Erinnerung: Ihre Übungen um 11:00", timeout=LOAD_MS)
        page.route("**/api/v1/patients/*", lambda route: route.abort() if route.request.method == "PATCH"
                   else route.continue_())  # fmt: skip
        switch = page.locator("#remind-emails")
        switch.click()
        expect(page.locator("#remind-saved")).to_contain_text("Nicht gespeichert:")
        expect(switch).to_be_checked()  # back as it was: nothing changed on the server
