"""GET /patients/{id}/progress and /patients/{id}/summary, and the summary's fixed query count for many patients."""

from __future__ import annotations

import datetime as dt

import pytest
from sqlalchemy import event

from backend.database import utcnow
from backend.plans.models import Plan, PlanItem
from backend.sessions import dashboard
from backend.suggestions.models import Suggestion


def test_week_start_is_monday_midnight_utc():
    sunday_evening = dt.datetime(2026, 11, 22, 23, 30, tzinfo=dt.UTC)
    assert dashboard.week_start(sunday_evening) == dt.datetime(2026, 11, 16, tzinfo=dt.UTC)
    assert dashboard.week_start(dt.datetime(2026, 11, 23, 0, 0, tzinfo=dt.UTC)) == dt.datetime(
        2026, 11, 23, tzinfo=dt.UTC
    )


def test_progress_is_oldest_first_per_exercise(client, make_user, auth_headers, exercise, other_exercise, store):
    patient = make_user("patient")
    t0 = dt.datetime(2026, 11, 1, 9, tzinfo=dt.UTC)
    late = store(patient, exercise, t0 + dt.timedelta(days=2), reps=12, rom=100.0)
    early = store(patient, exercise, t0, reps=8, rom=80.0)
    store(patient, other_exercise, t0 + dt.timedelta(days=1))
    response = client.get(
        f"/api/v1/patients/{patient.id}/progress", headers=auth_headers(patient), params={"exercise": exercise.slug}
    )
    assert response.status_code == 200, response.text
    points = response.json()["points"]
    assert [p["session_id"] for p in points] == [early.id, late.id]
    assert [(p["repetitions"], p["rom_deg"]) for p in points] == [(8, 80.0), (12, 100.0)]
    assert points[1]["indicators"]["flexibility"]["score"] == pytest.approx(50.0)


def test_progress_without_exercise_has_every_session(client, make_user, auth_headers, exercise, other_exercise, store):
    patient = make_user("patient")
    t0 = dt.datetime(2026, 11, 1, 9, tzinfo=dt.UTC)
    store(patient, exercise, t0)
    store(patient, other_exercise, t0 + dt.timedelta(hours=1), metrics=False)
    body = client.get(f"/api/v1/patients/{patient.id}/progress", headers=auth_headers(patient)).json()
    assert [p["exercise_slug"] for p in body["points"]] == [exercise.slug, other_exercise.slug]
    assert body["points"][1]["rom_deg"] is None and body["points"][1]["indicators"] is None


def test_progress_of_another_patient_is_403(client, make_user, auth_headers):
    patient, other = make_user("patient"), make_user("patient")
    assert client.get(f"/api/v1/patients/{other.id}/progress", headers=auth_headers(patient)).status_code == 403


def test_summary_counts_this_week_against_the_plan(
    client, db_session, make_patient_with_therapist, auth_headers, exercise, other_exercise, store
):
    patient, therapist = make_patient_with_therapist()
    now = utcnow()
    monday = dashboard.week_start(now)
    store(patient, exercise, monday - dt.timedelta(days=1))  # last week
    store(patient, exercise, monday + dt.timedelta(minutes=1), rom=70.0)
    newest = store(patient, other_exercise, monday + dt.timedelta(minutes=2), reps=9, rom=60.0)
    plan = Plan(patient_id=patient.id, therapist_id=therapist.id, title="p", start_date=now.date())
    plan.items = [
        PlanItem(exercise_id=exercise.id, sets=1, repetitions=10, frequency_per_week=3, position=0),
        PlanItem(exercise_id=other_exercise.id, sets=1, repetitions=10, frequency_per_week=2, position=1),
    ]
    db_session.add(plan)
    db_session.add_all(
        [
            Suggestion(patient_id=patient.id, source="system", rule="too_fast", text="a", status="pending"),
            Suggestion(patient_id=patient.id, source="system", rule="rom_drop", text="b", status="approved"),
        ]
    )
    db_session.flush()
    response = client.get(f"/api/v1/patients/{patient.id}/summary", headers=auth_headers(therapist))
    assert response.status_code == 200, response.text
    body = response.json()
    assert body["last_session"]["id"] == newest.id
    assert body["last_session"]["repetitions"] == 9
    assert (body["sessions_this_week"], body["planned_this_week"]) == (2, 5)
    assert body["latest_indicators"]["flexibility"]["value"] == pytest.approx(60.0)
    assert body["pending_suggestions"] == 1


def test_summary_of_a_patient_without_sessions(client, make_user, auth_headers):
    patient = make_user("patient")
    body = client.get(f"/api/v1/patients/{patient.id}/summary", headers=auth_headers(patient)).json()
    assert body == {
        "patient_id": patient.id,
        "last_session": None,
        "sessions_this_week": 0,
        "planned_this_week": None,
        "latest_indicators": None,
        "pending_suggestions": 0,
    }


def test_summaries_of_many_patients_take_two_queries(db_session, make_user, exercise, store):
    patients = [make_user("patient") for _ in range(20)]
    t0 = utcnow() - dt.timedelta(days=20)
    for i, patient in enumerate(patients):
        for k in range(5):
            store(patient, exercise, t0 + dt.timedelta(days=k, minutes=i), rom=50.0 + k)
    statements = []
    listener = lambda *args: statements.append(args[2])  # noqa: E731 - (conn, cursor, statement, ...)
    connection = db_session.connection()
    event.listen(connection, "before_cursor_execute", listener)
    try:
        result = dashboard.summaries(db_session=db_session, patient_ids=[p.id for p in patients], now=utcnow())
    finally:
        event.remove(connection, "before_cursor_execute", listener)
    assert len(statements) <= 2, statements
    assert all("file_bytes" not in s for s in statements)
    assert {r["latest_indicators"]["flexibility"]["value"] for r in result.values()} == {54.0}


def test_dashboard_lists_only_the_therapists_patients_with_their_summaries(
    client, make_user, make_patient_with_therapist, auth_headers, exercise, store
):
    patient, therapist = make_patient_with_therapist()
    make_patient_with_therapist()  # another therapist's patient
    newest = store(patient, exercise, utcnow() - dt.timedelta(minutes=5), reps=7, rom=64.0)
    response = client.get("/api/v1/dashboard", headers=auth_headers(therapist))
    assert response.status_code == 200, response.text
    body = response.json()
    assert (body["total"], [row["patient_id"] for row in body["items"]]) == (1, [patient.id])
    row = body["items"][0]
    assert (row["email"], row["last_session"]["id"], row["last_session"]["repetitions"]) == (
        patient.email,
        newest.id,
        7,
    )
    assert row["sessions_this_week"] >= 0 and row["pending_suggestions"] == 0
    assert row["latest_indicators"]["flexibility"]["value"] == pytest.approx(64.0)


def test_dashboard_pages_through_every_patient_for_an_admin(client, make_user, auth_headers):
    patients = [make_user("patient") for _ in range(3)]
    headers = auth_headers(make_user("admin"))
    total = client.get("/api/v1/dashboard", headers=headers, params={"limit": 1}).json()["total"]
    seen = []
    for offset in range(total):
        page = client.get("/api/v1/dashboard", headers=headers, params={"limit": 1, "offset": offset}).json()
        seen += [row["patient_id"] for row in page["items"]]
    assert set(p.id for p in patients) <= set(seen) and len(seen) == total == len(set(seen))


def test_dashboard_is_403_for_a_patient(client, make_user, auth_headers):
    response = client.get("/api/v1/dashboard", headers=auth_headers(make_user("patient")))
    assert response.status_code == 403
    assert response.json()["error"] == "Forbidden"


def test_dashboard_takes_a_fixed_number_of_queries(
    client, db_session, make_user, make_patient_with_therapist, auth_headers, exercise, store
):
    patient, therapist = make_patient_with_therapist()
    from backend.patients.models import TherapistPatient

    for _ in range(9):
        other = make_user("patient")
        db_session.add(TherapistPatient(therapist_id=therapist.id, patient_id=other.id, created_at=utcnow()))
        store(other, exercise, utcnow() - dt.timedelta(days=1))
    store(patient, exercise, utcnow() - dt.timedelta(days=1))
    db_session.flush()
    headers = auth_headers(therapist)
    statements = []
    listener = lambda *args: statements.append(args[2])  # noqa: E731 - (conn, cursor, statement, ...)
    connection = db_session.connection()
    event.listen(connection, "before_cursor_execute", listener)
    try:
        response = client.get("/api/v1/dashboard", headers=headers)
    finally:
        event.remove(connection, "before_cursor_execute", listener)
    assert response.status_code == 200 and response.json()["total"] == 10
    selects = [s for s in statements if s.lstrip().upper().startswith(("SELECT", "WITH"))]
    assert len(selects) <= 12, selects
    assert all("file_bytes" not in s for s in statements)


def test_dashboard_past_the_last_page_is_empty_with_the_total(client, make_patient_with_therapist, auth_headers):
    _, therapist = make_patient_with_therapist()
    body = client.get("/api/v1/dashboard", headers=auth_headers(therapist), params={"offset": 5}).json()
    assert (body["items"], body["total"], body["offset"]) == ([], 1, 5)
