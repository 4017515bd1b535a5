"""The therapist's patient page: the progress report's period form (the last 4 weeks by default), a bad period said
next to the form without a download, a good one downloaded as the PDF; by keyboard, labelled, at three widths."""

from __future__ import annotations

import datetime as dt
import shutil
import subprocess

import pytest
from axe_playwright_python.sync_playwright import Axe

from tests.frontend.conftest import SHOTS, THERAPIST, login, shot

pytestmark = pytest.mark.browser


def _serious(page) -> list[str]:
    return [v["id"] for v in Axe().run(page).response["violations"] if v["impact"] in ("serious", "critical")]


def _open(page, live_server) -> None:
    login(page, THERAPIST)
    page.wait_for_url("**/therapist")
    page.goto(f"/therapist/patients/{live_server.patient_id}")
    page.wait_for_selector("#sessions tbody tr[data-session-id]")


def _submit_by_keyboard(page) -> None:
    """Moves from the last day to the button with Tab, as a keyboard user does, and presses Enter (Tab first walks
    the date's own day, month and year)."""
    page.focus("#report-to")
    for _ in range(4):
        if page.evaluate("document.activeElement.id") != "report-to":
            break
        page.keyboard.press("Tab")
    assert page.evaluate("document.activeElement.id") == "report-paper"
    page.keyboard.press("Tab")
    assert page.evaluate("document.activeElement.id") == "report-download"
    page.keyboard.press("Enter")


def _form_fits(page) -> bool:
    """Returns whether the report form and each of its parts lie within the window's width (no sideways scroll)."""
    return page.evaluate("""(() => { const w = document.documentElement.clientWidth;
      const form = document.getElementById('report-form');
      return form.scrollWidth <= form.clientWidth
        && [form, ...form.querySelectorAll('*')].every((e) => e.getBoundingClientRect().right <= w); })()""")


def test_the_default_period_is_the_last_4_weeks_and_downloads_the_pdf(page, live_server):
    _open(page, live_server)
    today = dt.datetime.now(dt.UTC).date()
    assert page.input_value("#report-to") == today.isoformat()
    assert page.input_value("#report-from") == (today - dt.timedelta(days=27)).isoformat()
    for box, label in (("report-from", "First day"), ("report-to", "Last day"), ("report-paper", "Paper size")):
        assert page.inner_text(f"label[for={box}]") == label
    assert page.get_by_role("button", name="Download the report (PDF)").is_visible()
    assert page.get_by_role("form", name="Progress report (PDF)").is_visible()
    assert _serious(page) == []
    with page.expect_download() as info:
        _submit_by_keyboard(page)
    download = info.value
    start, end = today - dt.timedelta(days=27), today
    assert download.suggested_filename == f"progress-patient-{live_server.patient_id}-{start}-{end}.pdf"
    SHOTS.mkdir(parents=True, exist_ok=True)
    pdf = SHOTS / "report-period-default.pdf"
    download.save_as(pdf)
    assert pdf.read_bytes().startswith(b"%PDF")
    page.wait_for_selector("#report-state.note")
    assert "was handed to the browser's downloads" in page.inner_text("#report-state")
    assert page.locator("#report-err").is_hidden() and page.get_attribute("#report-from", "aria-invalid") is None
    if shutil.which("pdftoppm"):  # the first page, to look at (SHOTS/report-period-default-1.png)
        first = SHOTS / "report-period-default"
        subprocess.run(["pdftoppm", "-png", "-r", "60", "-f", "1", "-l", "1", str(pdf), str(first)], check=True)
    for width in (1366, 768, 390):
        page.set_viewport_size({"width": width, "height": 900})
        assert _form_fits(page), width
        page.locator("#report-form").scroll_into_view_if_needed()
        shot(page, f"report-period-ok-{width}")
    assert not page.js_errors


def test_a_bad_period_is_said_next_to_the_form_and_nothing_downloads(page, live_server):
    _open(page, live_server)
    downloads = []
    page.on("download", lambda d: downloads.append(d))
    page.fill("#report-from", "2026-11-20")
    page.fill("#report-to", "2026-11-01")
    _submit_by_keyboard(page)
    err = page.locator("#report-err")
    err.wait_for(state="visible")
    assert "The first day (20 November 2026) is after the last day (1 November 2026)" in err.inner_text()
    assert page.get_attribute("#report-from", "aria-invalid") == "true"
    assert page.get_attribute("#report-to", "aria-invalid") == "true"
    assert page.evaluate("document.activeElement.id") == "report-from", "the focus goes to the field to fix"
    assert page.get_attribute("#report-err", "role") == "alert"
    assert "report-err" in page.get_attribute("#report-from", "aria-describedby")
    assert _serious(page) == []
    for width in (1366, 768, 390):
        page.set_viewport_size({"width": width, "height": 900})
        assert _form_fits(page), width
        page.locator("#report-form").scroll_into_view_if_needed()
        shot(page, f"report-period-bad-{width}")
    page.set_viewport_size({"width": 1366, "height": 900})
    page.fill("#report-from", "2026-10-01")
    assert err.is_hidden() and page.get_attribute("#report-from", "aria-invalid") is None, "typing clears the error"
    for start, end, says in (
        ("", "2026-11-01", "Choose the first day of the report"),
        ("2026-10-01", "", "Choose the last day of the report"),
        ("", "", "the period is empty"),
        ("2020-01-01", "2026-11-01", "at most 3 years"),
    ):
        page.fill("#report-from", start)
        page.fill("#report-to", end)
        page.click("#report-download")
        err.wait_for(state="visible")
        assert says in err.inner_text(), (start, end, err.inner_text())
    page.wait_for_timeout(500)
    assert downloads == [], "a bad period downloads nothing"
    page.fill("#report-from", "2026-10-01")
    page.fill("#report-to", "2026-10-31")
    page.select_option("#report-paper", "letter")
    with page.expect_download() as info:
        page.click("#report-download")
    assert info.value.suggested_filename.endswith("-2026-10-01-2026-10-31.pdf")
    assert err.is_hidden()
    assert not page.js_errors
