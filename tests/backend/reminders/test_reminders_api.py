"""Reminder fields of the API: plan reminder times, the patient's time zone, today's reminders, and what bad input
is told; the server's own loop sends a due reminder."""

from __future__ import annotations

import datetime as dt
import uuid
from typing import Any

import pytest
from fastapi.testclient import TestClient
from sqlalchemy import delete
from sqlalchemy.orm import sessionmaker

from backend.database import utcnow
from backend.main import create_app
from backend.plans.models import Plan
from backend.reminders.times import due_at, local_date, zone
from backend.users.models import User
from tests.backend.reminders.conftest import mail_settings


def _plan(exercise, **more) -> dict[str, Any]:
    item = {"exercise_slug": exercise.slug, "sets": 1, "repetitions": 5, "frequency_per_week": 2}
    return {"title": "p", "start_date": "2026-11-01", "items": [item]} | more


def test_a_plan_keeps_its_reminder_times_sorted(client, make_patient_with_therapist, auth_headers, exercise):
    patient, therapist = make_patient_with_therapist()
    headers = auth_headers(therapist)
    r = client.post(f"/api/v1/patients/{patient.id}/plans", json=_plan(exercise, reminder_times=["18:30", "08:00"]),
                    headers=headers)  # fmt: skip
    assert r.status_code == 201, r.text
    assert r.json()["reminder_times"] == ["08:00", "18:30"]
    plan_id = r.json()["id"]
    r = client.put(f"/api/v1/plans/{plan_id}", json=_plan(exercise), headers=headers)  # no times: none
    assert r.status_code == 200 and r.json()["reminder_times"] == []


@pytest.mark.parametrize(
    ("times", "says"),
    [
        (["25:00"], "body.reminder_times: Value error, reminder time '25:00' is not a time like 08:30 (HH:MM"),
        (["08:00", "08:00"], "body.reminder_times: Value error, reminder time 08:00 is given twice"),
        ([8], "body.reminder_times.0: Input should be a valid string"),
        (["1"] * 7, "body.reminder_times: List should have at most 6 items"),
    ],
)
def test_bad_reminder_times_say_what_was_wrong(client, make_patient_with_therapist, auth_headers, exercise, times,
                                               says):  # fmt: skip
    patient, therapist = make_patient_with_therapist()
    r = client.post(f"/api/v1/patients/{patient.id}/plans", json=_plan(exercise, reminder_times=times),
                    headers=auth_headers(therapist))  # fmt: skip
    assert r.status_code == 422
    assert r.json()["error"] == "ValidationError"
    assert says in r.json()["detail"], r.json()["detail"]


def test_the_patient_time_zone_is_set_and_validated(client, make_patient_with_therapist, auth_headers):
    patient, therapist = make_patient_with_therapist()
    headers = auth_headers(therapist)
    r = client.patch(f"/api/v1/patients/{patient.id}", json={"time_zone": "Europe/Madrid"}, headers=headers)
    assert r.status_code == 200 and r.json()["time_zone"] == "Europe/Madrid"
    assert r.json()["locale"] is None  # a field not sent is not changed
    r = client.patch(f"/api/v1/patients/{patient.id}", json={"locale": "es"}, headers=headers)
    assert r.json()["time_zone"] == "Europe/Madrid" and r.json()["locale"] == "es"
    r = client.patch(f"/api/v1/patients/{patient.id}", json={"time_zone": "Europe/Madird"}, headers=headers)
    assert r.status_code == 422
    assert r.json()["detail"] == (
        "body.time_zone: Value error, time zone 'Europe/Madird' is not an IANA time zone name like Europe/Berlin "
        "or America/New_York"
    )
    assert client.patch(f"/api/v1/patients/{patient.id}", json={}, headers=headers).status_code == 422
    r = client.patch(f"/api/v1/patients/{patient.id}", json={"timezone": "UTC"}, headers=headers)
    assert r.status_code == 422 and "timezone: Extra inputs are not permitted" in r.json()["detail"]


def test_today_lists_the_times_in_the_patients_zone_and_the_next(client, db_session, make_user, auth_headers):
    patient = make_user("patient")
    patient.time_zone = "Pacific/Kiritimati"  # UTC+14: its day is rarely the server's
    plan = Plan(patient_id=patient.id, title="p", start_date=dt.date(2026, 1, 1), reminder_times=["00:00", "23:59"])
    db_session.add(plan)
    db_session.flush()
    before = utcnow()
    r = client.get(f"/api/v1/patients/{patient.id}/reminders", headers=auth_headers(patient))
    assert r.status_code == 200
    out = r.json()
    tz = zone("Pacific/Kiritimati")
    day = local_date(before, tz)
    assert out["time_zone"] == "Pacific/Kiritimati" and out["local_date"] == day.isoformat()
    assert [t["time"] for t in out["times"]] == ["00:00", "23:59"]
    assert [dt.datetime.fromisoformat(t["due_at"]) for t in out["times"]] == [due_at(day, "00:00", tz),
                                                                              due_at(day, "23:59", tz)]  # fmt: skip
    assert out["times"][0]["passed"] is True
    assert out["next"] == (out["times"][1] if not out["times"][1]["passed"] else None)
    assert out["emails"] is False  # no SMTP server configured


def test_a_patient_without_a_zone_follows_the_servers(db_session, make_user, auth_headers, settings):
    from tests.backend.conftest import make_test_app

    patient = make_user("patient")
    db_session.add(Plan(patient_id=patient.id, title="p", start_date=dt.date(2026, 1, 1), reminder_times=["12:00"]))
    db_session.flush()
    app = make_test_app(db_session, settings.model_copy(update={"TIME_ZONE": "Asia/Tokyo"}))
    out = TestClient(app).get(f"/api/v1/patients/{patient.id}/reminders", headers=auth_headers(patient)).json()
    assert out["time_zone"] == "Asia/Tokyo"
    assert dt.datetime.fromisoformat(out["times"][0]["due_at"]).hour == 3  # 12:00 in Tokyo is 03:00 UTC


def test_the_server_refuses_smtp_without_sender_and_public_url():
    from backend.config import Settings

    with pytest.raises(ValueError, match="COACH_SMTP_HOST needs COACH_SMTP_FROM"):
        Settings(SMTP_HOST="smtp.example.org")
    with pytest.raises(ValueError, match="time zone 'Mars/Olympus' is not an IANA time zone"):
        Settings(TIME_ZONE="Mars/Olympus")


def test_the_running_server_sends_a_due_reminder_by_itself(engine, smtp):
    """The app's lifespan runs the reminder loop when SMTP is configured: a reminder due a minute ago arrives."""
    inbox, port = smtp
    factory = sessionmaker(bind=engine, expire_on_commit=False)
    now = utcnow()
    with factory() as db:
        patient = User(email=f"loop-{uuid.uuid4().hex[:8]}@example.org", role="patient", time_zone="UTC")
        db.add(patient)
        db.flush()
        db.add(Plan(patient_id=patient.id, title="Loop plan", start_date=now.date() - dt.timedelta(days=1),
                    reminder_times=[(now - dt.timedelta(minutes=1)).strftime("%H:%M")]))  # fmt: skip
        db.commit()
    try:
        app = create_app(mail_settings(port, REMINDER_CHECK_S=0.2), engine=engine)
        with TestClient(app):
            (msg,) = inbox.wait_for(1, timeout_s=20)
        assert inbox.recipients == [[patient.email]]
        assert "Loop plan" in msg.get_content()
    finally:
        with factory() as db:
            db.execute(delete(User).where(User.id == patient.id))
            db.commit()
