"""Reminder e-mails: due at the patient's local time, sent once, received by a real SMTP server, in the patient's
language, with an unsubscribe link that works without login and stops the e-mails."""

from __future__ import annotations

import datetime as dt
import re
from contextlib import nullcontext

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import select

from backend.plans.models import Plan
from backend.reminders.models import ReminderSent
from backend.reminders.sender import send_due
from tests.backend.conftest import make_test_app
from tests.backend.reminders.conftest import PUBLIC_URL, free_port, mail_settings

UTC = dt.UTC
BERLIN_EIGHT_IN_WINTER = dt.datetime(2026, 11, 27, 7, 0, tzinfo=UTC)  # 08:00 in Europe/Berlin


@pytest.fixture
def patient_plan(db_session, make_user):
    """A German-speaking patient in Europe/Berlin with a plan that reminds at 08:00 and 18:30 (committed)."""
    patient = make_user("patient", full_name="Anna Berg")
    patient.locale, patient.time_zone = "de", "Europe/Berlin"
    plan = Plan(patient_id=patient.id, title="Knie, Woche 1-4", start_date=dt.date(2026, 11, 1),
                reminder_times=["08:00", "18:30"])  # fmt: skip
    db_session.add(plan)
    db_session.commit()
    return patient, plan


def _send(db_session, settings, now) -> int:
    return send_due(sessions=lambda: nullcontext(db_session), settings=settings, now=now)


def _link(message) -> str:
    found = re.search(re.escape(PUBLIC_URL) + r"/unsubscribe/(\S+)", message.get_content())
    assert found, message.get_content()
    return found.group(0)


def test_a_due_reminder_reaches_the_smtp_server_in_the_patients_language(db_session, smtp, patient_plan):
    inbox, port = smtp
    patient, plan = patient_plan
    assert _send(db_session, mail_settings(port), BERLIN_EIGHT_IN_WINTER + dt.timedelta(seconds=20)) == 1
    (msg,) = inbox.wait_for(1)
    assert inbox.recipients == [[patient.email]]
    assert msg["Subject"] == "Erinnerung: Ihre Übungen um 08:00"
    assert msg["Content-Language"] == "de"
    body = msg.get_content()
    assert "Hallo Anna," in body and "es ist Zeit für Ihre Übungen (08:00): Knie, Woche 1-4." in body
    assert msg["List-Unsubscribe"] == f"<{_link(msg)}>"
    assert msg["List-Unsubscribe-Post"] == "List-Unsubscribe=One-Click"
    row = db_session.scalar(select(ReminderSent).where(ReminderSent.plan_id == plan.id))
    assert (row.local_date, row.local_time, row.due_at) == (dt.date(2026, 11, 27), "08:00", BERLIN_EIGHT_IN_WINTER)
    assert row.sent_at is not None


def test_nothing_is_due_a_second_before_the_local_time(db_session, smtp, patient_plan):
    inbox, port = smtp
    assert _send(db_session, mail_settings(port), BERLIN_EIGHT_IN_WINTER - dt.timedelta(seconds=1)) == 0
    assert inbox.messages == []


def test_on_the_spring_change_eight_oclock_is_due_at_six_utc(db_session, smtp, patient_plan):
    inbox, port = smtp
    settings = mail_settings(port)
    assert _send(db_session, settings, dt.datetime(2026, 3, 29, 5, 59, 59, tzinfo=UTC)) == 0  # 07:59:59 summer time
    patient_plan[1].start_date = dt.date(2026, 3, 1)
    db_session.commit()
    assert _send(db_session, settings, dt.datetime(2026, 3, 29, 5, 59, 59, tzinfo=UTC)) == 0
    assert _send(db_session, settings, dt.datetime(2026, 3, 29, 6, 0, 0, tzinfo=UTC)) == 1
    assert inbox.wait_for(1)[0]["Subject"].endswith("08:00")


def test_each_reminder_is_sent_once_however_often_the_server_checks(db_session, smtp, patient_plan):
    inbox, port = smtp
    settings = mail_settings(port)
    sent = [_send(db_session, settings, BERLIN_EIGHT_IN_WINTER + dt.timedelta(minutes=m)) for m in range(0, 60, 5)]
    assert sent == [1] + [0] * 11
    assert len(inbox.wait_for(1)) == 1


def test_a_reminder_missed_for_longer_than_the_late_window_is_dropped(db_session, smtp, patient_plan):
    inbox, port = smtp
    later = BERLIN_EIGHT_IN_WINTER + dt.timedelta(minutes=61)  # the server was down from 07:59 to 09:01
    assert _send(db_session, mail_settings(port, REMINDER_LATE_MINUTES=60), later) == 0
    assert inbox.messages == []


def test_a_failed_delivery_is_tried_again_at_the_next_check(db_session, smtp, patient_plan):
    inbox, port = smtp
    now = BERLIN_EIGHT_IN_WINTER + dt.timedelta(seconds=5)
    assert _send(db_session, mail_settings(free_port()), now) == 0  # no SMTP server there: connection refused
    assert db_session.scalars(select(ReminderSent)).all() == []  # the claim was given back
    assert _send(db_session, mail_settings(port), now + dt.timedelta(minutes=1)) == 1
    assert len(inbox.wait_for(1)) == 1


def test_the_unsubscribe_link_works_without_login_and_stops_further_emails(db_session, smtp, patient_plan, settings):
    inbox, port = smtp
    patient, _ = patient_plan
    mailing = mail_settings(port)
    assert _send(db_session, mailing, BERLIN_EIGHT_IN_WINTER) == 1
    link = _link(inbox.wait_for(1)[0])
    path = link.removeprefix(PUBLIC_URL)
    client = TestClient(make_test_app(db_session, mailing), raise_server_exceptions=False)  # no login, no lifespan
    page = client.get(path, headers={"Accept": "text/html"})
    assert page.status_code == 200
    assert "E-Mail-Erinnerungen abbestellen?" in page.text  # the patient's language, a button, nothing changed yet
    assert f'action="/clinic{path}"' in page.text
    db_session.refresh(patient)
    assert patient.reminder_emails_off_at is None
    done = client.post(path)
    assert done.status_code == 200 and "Keine E-Mail-Erinnerungen mehr" in done.text
    db_session.refresh(patient)
    first = patient.reminder_emails_off_at
    assert first is not None
    again = client.post(path)  # idempotent: the same answer, the first time kept
    assert again.status_code == 200
    db_session.refresh(patient)
    assert patient.reminder_emails_off_at == first
    api = client.post("/api/v1/reminders/unsubscribe/" + path.rsplit("/", 1)[1])
    assert api.status_code == 200 and api.json()["unsubscribed"] is True
    assert dt.datetime.fromisoformat(api.json()["since"]) == first
    assert _send(db_session, mailing, BERLIN_EIGHT_IN_WINTER + dt.timedelta(hours=10, minutes=30)) == 0  # 18:30
    assert _send(db_session, mailing, BERLIN_EIGHT_IN_WINTER + dt.timedelta(days=1)) == 0  # tomorrow 08:00
    assert len(inbox.messages) == 1


def test_an_unknown_unsubscribe_link_is_not_found(client):
    token = "unsub_" + "x" * 43
    r = client.post(f"/api/v1/reminders/unsubscribe/{token}")
    assert r.status_code == 404
    detail = "this unsubscribe link belongs to no reminder e-mail; check that it is complete"
    assert r.json() == {"error": "UnsubscribeLinkUnknown", "detail": detail}
    page = client.get(f"/unsubscribe/{token}", headers={"Accept": "text/html"})
    assert page.status_code == 404 and "Link not found" in page.text
    assert client.post(f"/unsubscribe/{token}").status_code == 404


def test_the_therapist_can_turn_emails_on_again(db_session, smtp, patient_plan, client, make_user, auth_headers):
    inbox, port = smtp
    patient, _ = patient_plan
    patient.reminder_emails_off_at = BERLIN_EIGHT_IN_WINTER
    db_session.commit()
    assert _send(db_session, mail_settings(port), BERLIN_EIGHT_IN_WINTER) == 0
    r = client.patch(f"/api/v1/patients/{patient.id}", json={"reminder_emails": True},
                     headers=auth_headers(make_user("admin")))  # fmt: skip
    assert r.status_code == 200 and r.json()["reminder_emails"] is True
    assert _send(db_session, mail_settings(port), BERLIN_EIGHT_IN_WINTER) == 1


def test_only_the_plan_running_that_day_reminds(db_session, smtp, patient_plan):
    inbox, port = smtp
    patient, old = patient_plan
    newer = Plan(patient_id=patient.id, title="Neu", start_date=dt.date(2026, 11, 20), reminder_times=[])
    db_session.add(newer)
    db_session.commit()
    assert _send(db_session, mail_settings(port), BERLIN_EIGHT_IN_WINTER) == 0  # the newer plan has no reminders
    newer.reminder_times = ["08:00"]
    db_session.commit()
    assert _send(db_session, mail_settings(port), BERLIN_EIGHT_IN_WINTER) == 1
    assert inbox.wait_for(1)[0].get_content().count("Neu") == 1
    newer.end_date = dt.date(2026, 11, 27)
    old.end_date = dt.date(2026, 11, 27)
    db_session.commit()
    assert _send(db_session, mail_settings(port), BERLIN_EIGHT_IN_WINTER + dt.timedelta(days=1)) == 0  # both ended
