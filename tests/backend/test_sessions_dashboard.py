"""GET /patients/{id}/progress and /patients/{id}/summary, and the summary's fixed query count for many patients."""

from __future__ import annotations

import datetime as dt
from typing import Any

import pytest
from sqlalchemy import event

from backend.database import utcnow
from backend.exercises.library import LIBRARY
from backend.i18n import Translator
from backend.plans.models import Plan, PlanItem
from backend.session_review import dashboard
from backend.sessions import triage
from backend.suggestions.models import Suggestion
from tests.backend.session_rows import document


def test_week_start_is_monday_midnight_utc():
    sunday_evening = dt.datetime(2026, 11, 22, 23, 30, tzinfo=dt.UTC)
    assert triage.week_start(sunday_evening) == dt.datetime(2026, 11, 16, tzinfo=dt.UTC)
    assert triage.week_start(dt.datetime(2026, 11, 23, 0, 0, tzinfo=dt.UTC)) == dt.datetime(2026, 11, 23, tzinfo=dt.UTC)


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


def test_progress_carries_the_pain_and_effort_the_patient_said(client, make_user, auth_headers, exercise, store):
    patient = make_user("patient")
    headers = auth_headers(patient)
    t0 = dt.datetime(2026, 11, 1, 9, tzinfo=dt.UTC)
    said, skipped, unasked = (store(patient, exercise, t0 + dt.timedelta(days=d)) for d in range(3))
    for session, answer in ((said, {"pain": 4, "effort": 6.5}), (skipped, {"pain": None, "effort": 2.0})):
        r = client.put(f"/api/v1/sessions/{session.id}/feeling", json=answer, headers=headers)
        assert r.status_code == 200, r.text
    points = client.get(f"/api/v1/patients/{patient.id}/progress", headers=headers).json()["points"]
    assert [(p["session_id"], p["pain_nrs"], p["effort_cr10"]) for p in points] == [
        (said.id, 4, 6.5), (skipped.id, None, 2.0), (unasked.id, None, None)
    ]  # fmt: skip


def test_progress_of_another_patient_is_404(client, make_user, auth_headers):
    patient, other = make_user("patient"), make_user("patient")
    assert client.get(f"/api/v1/patients/{other.id}/progress", headers=auth_headers(patient)).status_code == 404


def test_summary_counts_this_week_against_the_plan(
    client, db_session, make_patient_with_therapist, auth_headers, exercise, other_exercise, store
):
    patient, therapist = make_patient_with_therapist()
    now = utcnow()
    monday = triage.week_start(now)
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
    trends = body.pop("indicator_trends")
    assert body == {
        "patient_id": patient.id,
        "last_session": None,
        "sessions_this_week": 0,
        "planned_this_week": None,
        "latest_indicators": None,
        "pending_suggestions": 0,
        "unread_replies": 0,
        "attention_score": 0,
        "attention_level": "ok",
        "attention_reasons": [],
        "balance_missing": "Not measured: no analysed session yet",
    }
    assert set(trends) == {"flexibility", "endurance", "strength", "balance"}
    assert all(t["direction"] is None and t["weekly_median"] == [None] * 6 for t in trends.values())


def test_summaries_of_many_patients_take_three_queries(db_session, make_user, exercise, store):
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
    assert len(statements) <= 3, statements
    assert all("file_bytes" not in s for s in statements)
    assert {r["latest_indicators"].flexibility.value for r in result.values()} == {54.0}


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


# ------------------------------------------------------------------------------------------------ triage

THURSDAY_NOON = dt.datetime(2026, 11, 26, 12, 0, tzinfo=dt.UTC)  # week of Monday 23 Nov


def _plan(db_session, patient, therapist, exercise, start: dt.date, per_week: int = 3) -> Plan:
    plan = Plan(patient_id=patient.id, therapist_id=therapist.id, title="home", start_date=start)
    plan.items = [PlanItem(exercise_id=exercise.id, sets=1, repetitions=10, frequency_per_week=per_week, position=0)]
    db_session.add(plan)
    db_session.flush()
    return plan


def _on_plan_history(store, patient, exercise, *, recent_rom: float = 90.0, recent_reps: int = 10) -> None:
    """Monday, Wednesday and Friday sessions for five weeks before THURSDAY_NOON's week, then Mon and Wed of it."""
    monday = triage.week_start(THURSDAY_NOON)
    for week in range(5, 0, -1):
        for day in (0, 2, 4):
            store(patient, exercise, monday - week * dt.timedelta(days=7) + dt.timedelta(days=day, hours=10))
    for day in (0, 2):
        store(patient, exercise, monday + dt.timedelta(days=day, hours=10), rom=recent_rom, reps=recent_reps)


def _summary(db_session, patient, now=THURSDAY_NOON) -> dict[str, Any]:
    return dashboard.summaries(db_session=db_session, patient_ids=[patient.id], now=now)[patient.id]


def test_a_patient_on_plan_with_every_session_done_scores_low(db_session, make_patient_with_therapist, exercise, store):
    patient, therapist = make_patient_with_therapist()
    _plan(db_session, patient, therapist, exercise, THURSDAY_NOON.date() - dt.timedelta(days=40))
    _on_plan_history(store, patient, exercise)
    row = _summary(db_session, patient)
    assert (row["attention_score"], row["attention_level"], row["attention_reasons"]) == (0, "ok", [])
    assert row["indicator_trends"]["flexibility"]["direction"] == "flat"
    assert row["indicator_trends"]["flexibility"]["weekly_median"] == [45.0] * 6


def test_a_falling_range_of_motion_scores_higher_with_the_reason_in_words(
    db_session, make_patient_with_therapist, exercise, store
):
    patient, therapist = make_patient_with_therapist()
    _plan(db_session, patient, therapist, exercise, THURSDAY_NOON.date() - dt.timedelta(days=40))
    _on_plan_history(store, patient, exercise, recent_rom=60.0)
    row = _summary(db_session, patient)
    name = LIBRARY[exercise.slug].name  # the library's name, as the pages show it
    expected = round(35 * ((90 - 60) / 90 - 0.10) / 0.30)
    assert row["attention_score"] == expected and row["attention_level"] == "soon", row
    assert row["attention_reasons"] == [
        f"Range of motion of {name} fell from 90° to 60° (median of the last 7 days against the 4 weeks before)"
    ]
    assert row["indicator_trends"]["flexibility"]["direction"] == "down"
    assert row["indicator_trends"]["flexibility"]["text"] == "Flexibility fell from 45 to 30 over 5 weeks"


def test_falling_repetitions_are_a_reason_and_poor_quality_sessions_do_not_count_as_a_fall(
    db_session, make_patient_with_therapist, exercise, store
):
    patient, therapist = make_patient_with_therapist()
    _plan(db_session, patient, therapist, exercise, THURSDAY_NOON.date() - dt.timedelta(days=40))
    _on_plan_history(store, patient, exercise, recent_reps=5)
    store(patient, exercise, THURSDAY_NOON - dt.timedelta(hours=1), rom=20.0, reps=1, quality_ok=False)
    row = _summary(db_session, patient)
    name = LIBRARY[exercise.slug].name
    assert row["attention_reasons"] == [
        f"Repetitions of {name} fell from 10 to 5 (median of the last 7 days against the 4 weeks before)",
        "1 of the last 5 sessions recorded with poor tracking quality",
    ]
    assert row["attention_score"] == round(35 + 15 / 5)


def test_a_new_patient_without_sessions_is_not_now_but_an_absent_one_is(
    db_session, make_patient_with_therapist, exercise
):
    new, therapist = make_patient_with_therapist()
    _plan(db_session, new, therapist, exercise, THURSDAY_NOON.date() - dt.timedelta(days=1), per_week=7)
    db_session.add_all(
        [Suggestion(patient_id=new.id, source="system", rule="r", text="t", status="pending") for _ in range(3)]
    )
    absent, _ = make_patient_with_therapist()
    _plan(db_session, absent, therapist, exercise, THURSDAY_NOON.date() - dt.timedelta(days=21))
    db_session.flush()
    rows = dashboard.summaries(db_session=db_session, patient_ids=[new.id, absent.id], now=THURSDAY_NOON)
    assert rows[new.id]["attention_level"] != "now", rows[new.id]
    assert rows[new.id]["attention_reasons"][-1] == "New plan since 25 Nov; no session yet"
    assert rows[absent.id]["attention_level"] == "now", rows[absent.id]
    assert rows[absent.id]["attention_reasons"][0] == "No session at all since the plan started on 5 Nov"


def test_monday_morning_is_not_behind_the_plan(db_session, make_patient_with_therapist, exercise, store):
    patient, therapist = make_patient_with_therapist()
    _plan(db_session, patient, therapist, exercise, THURSDAY_NOON.date() - dt.timedelta(days=40), per_week=6)
    monday_morning = triage.week_start(THURSDAY_NOON) + dt.timedelta(hours=8)
    store(patient, exercise, monday_morning - dt.timedelta(days=2))
    row = _summary(db_session, patient, now=monday_morning)
    assert (row["attention_score"], row["attention_reasons"]) == (0, [])
    thursday = _summary(db_session, patient)
    assert (
        thursday["attention_reasons"][0]
        == "Behind this week's plan: 0 of the 3 sessions due by now done (6 a week planned)"
    )


def test_missing_balance_is_explained_in_words(db_session, make_user, exercise, store):
    patient = make_user("patient")
    store(patient, exercise, THURSDAY_NOON - dt.timedelta(days=1))
    row = _summary(db_session, patient)
    name = LIBRARY[exercise.slug].name
    assert row["balance_missing"] == (f"Not measured: no still standing of 2 s or more in the last session ({name})")
    doc = document(reps=5, rom=50.0, quality_ok=True, exercise=exercise.slug)
    doc["indicators"]["balance"]["score"] = 80.0
    store(patient, exercise, THURSDAY_NOON - dt.timedelta(hours=1), doc=doc)
    assert _summary(db_session, patient)["balance_missing"] is None


def test_dashboard_is_sorted_by_attention_then_name_and_pages(client, db_session, make_user, auth_headers, exercise):
    from backend.patients.models import TherapistPatient

    therapist = make_user("therapist")
    calm, pending, absent = (make_user("patient", full_name=n) for n in ("Aaron Calm", "Bea Pending", "Zed Absent"))
    for p in (calm, pending, absent):
        db_session.add(TherapistPatient(therapist_id=therapist.id, patient_id=p.id, created_at=utcnow()))
    db_session.add_all(
        [Suggestion(patient_id=pending.id, source="system", rule="r", text="t", status="pending") for _ in range(3)]
    )
    _plan(db_session, absent, therapist, exercise, utcnow().date() - dt.timedelta(days=30))
    headers = auth_headers(therapist)
    items = client.get("/api/v1/dashboard", headers=headers).json()["items"]
    assert [r["patient_id"] for r in items] == [absent.id, pending.id, calm.id]
    scores = [r["attention_score"] for r in items]
    assert scores == sorted(scores, reverse=True) and scores[-1] == 0 and scores[1] == 10, scores
    page = client.get("/api/v1/dashboard", headers=headers, params={"limit": 1, "offset": 1}).json()
    assert ([r["patient_id"] for r in page["items"]], page["total"]) == ([pending.id], 3)


def test_dashboard_queries_do_not_grow_with_patients(client, db_session, make_user, auth_headers, exercise, store):
    from backend.patients.models import TherapistPatient

    therapist = make_user("therapist")
    headers = auth_headers(therapist)

    def add_patients(n: int) -> None:
        for _ in range(n):
            patient = make_user("patient")
            db_session.add(TherapistPatient(therapist_id=therapist.id, patient_id=patient.id, created_at=utcnow()))
            _plan(db_session, patient, therapist, exercise, utcnow().date() - dt.timedelta(days=30))
            for k in range(4):
                store(patient, exercise, utcnow() - dt.timedelta(days=3 + 5 * k))
        db_session.flush()

    def count_selects() -> int:
        statements = []
        listener = lambda *args: statements.append(args[2])  # noqa: E731 - (conn, cursor, statement, ...)
        connection = db_session.connection()
        event.listen(connection, "before_cursor_execute", listener)
        try:
            assert client.get("/api/v1/dashboard", headers=headers).status_code == 200
        finally:
            event.remove(connection, "before_cursor_execute", listener)
        return sum(1 for s in statements if s.lstrip().upper().startswith(("SELECT", "WITH")))

    add_patients(2)
    few = count_selects()
    add_patients(10)
    assert count_selects() == few


def test_missing_balance_gives_the_analysis_reason_in_the_readers_language(db_session, make_user, exercise, store):
    patient = make_user("patient")
    why: dict[str, Any] = {"id": "not_standing", "params": {}, "text": None}  # as schema 3 stores it
    doc = document(reps=5, rom=50.0, quality_ok=True, exercise=exercise.slug) | {
        "balance": None,
        "balance_missing": why,
    }
    doc["indicators"]["balance"] |= {"score": None, "value": None, "interval": None, "missing": why}
    store(patient, exercise, THURSDAY_NOON - dt.timedelta(hours=1), doc=doc)
    name = triage._name(exercise.slug)  # the library's name, as the triage reasons say it
    english = "the patient was seated or crouching: balance is measured while standing"
    summary = _summary(db_session, patient)
    assert summary["balance_missing"] == f"Not measured ({name}): {english}"
    assert summary["latest_indicators"].balance.missing.text == english
    german = dashboard.summaries(db_session=db_session, patient_ids=[patient.id], now=THURSDAY_NOON,
                                 t=Translator("de", therapist=True))[patient.id]  # fmt: skip
    said = "es wurde im Sitzen oder in der Hocke geübt: das Gleichgewicht wird im Stehen gemessen"
    assert german["balance_missing"].endswith(f": {said}"), "the analysis' reason in the messages' German"
    assert german["latest_indicators"].balance.missing.text == said


def test_advice_to_review_alone_does_not_make_a_patient_soon(db_session, make_patient_with_therapist, exercise, store):
    patient, therapist = make_patient_with_therapist()
    _plan(db_session, patient, therapist, exercise, THURSDAY_NOON.date() - dt.timedelta(days=40))
    _on_plan_history(store, patient, exercise)
    db_session.add_all(
        [Suggestion(patient_id=patient.id, source="system", rule="r", text="t", status="pending") for _ in range(4)]
    )
    db_session.flush()
    row = _summary(db_session, patient)
    assert row["attention_level"] == "ok" and row["attention_reasons"] == ["4 suggestions to review"], row


def test_a_fall_is_never_worded_as_from_a_number_to_the_same_number():
    from backend.sessions.triage import RecentSession, attention

    def at(days_ago: float, reps: int) -> RecentSession:
        return RecentSession(THURSDAY_NOON - dt.timedelta(days=days_ago), "squat", reps, None, True, None)

    # baseline median 8.5, recent median 7.5: a 12 % drop, whole numbers would both read 8
    sessions = [at(20, 8), at(18, 9), at(3, 7), at(2, 8)]
    found = attention(now=THURSDAY_NOON, plan=None, sessions_this_week=2, last_session_at=THURSDAY_NOON,
                      sessions=sessions, pending_suggestions=0)  # fmt: skip
    assert found.reasons == [
        "Repetitions of Mini squat fell from 8.5 to 7.5 (median of the last 7 days against the 4 weeks before)"
    ], found.reasons
