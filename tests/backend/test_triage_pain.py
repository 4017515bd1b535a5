"""The pain a patient says after a set (0-10, backend.feeling) raises their attention score with the reason in
words: high pain at once, a rising median over the weeks (backend.sessions.triage, module doc "pain")."""

from __future__ import annotations

import datetime as dt
from typing import Any

import pytest

from backend.feeling.models import SessionFeeling
from backend.session_review import dashboard
from backend.sessions.triage import NOW_AT, SOON_AT, RecentSession, attention

THURSDAY_NOON = dt.datetime(2026, 11, 26, 12, 0, tzinfo=dt.UTC)


def _at(days_ago: float, pain: int | None) -> RecentSession:
    return RecentSession(THURSDAY_NOON - dt.timedelta(days=days_ago), "squat", 10, 90.0, True, None, pain)


def _attention(sessions, **kw):
    return attention(now=THURSDAY_NOON, plan=None, sessions_this_week=2, last_session_at=THURSDAY_NOON,
                     sessions=sessions, pending_suggestions=0, **kw)  # fmt: skip


def test_high_pain_in_the_last_week_makes_the_patient_soon_with_the_day_and_exercise():
    found = _attention([_at(20, 1), _at(3, 2), _at(1, 7)])
    assert found.score == 30 and found.level == "soon", found
    assert found.reasons == ["Said pain 7 of 10 after Mini squat on 25 Nov (alert above 5)"], found.reasons


def test_the_patients_own_alert_level_decides_what_pain_counts_as_high():
    sessions = [_at(20, 1), _at(3, 2), _at(1, 4)]
    assert _attention(sessions).score == 0  # 4 is not above the default alert level (5)
    found = _attention(sessions, pain_alert_above=3)
    assert found.score == 30 and found.reasons == ["Said pain 4 of 10 after Mini squat on 25 Nov (alert above 3)"]
    assert _attention([_at(1, 7)], pain_alert_above=7).score == 0  # a patient whose pain of 7 is their normal


def test_a_rising_median_of_pain_is_said_with_both_medians():
    found = _attention([_at(25, 1), _at(20, 2), _at(12, 1), _at(4, 4), _at(2, 4)])
    assert found.score == 25 and SOON_AT <= found.score < NOW_AT, found
    assert found.reasons == [
        "Pain after sets rose from 1 to 4 of 10 (median of the last 7 days against the 4 weeks before)"
    ], found.reasons


def test_low_steady_or_unsaid_pain_adds_nothing():
    assert _attention([_at(20, 2), _at(15, 2), _at(3, 3), _at(1, None)]).score == 0
    assert _attention([_at(3, None)]).score == 0


def test_the_dashboard_reads_the_pain_stored_with_a_session(db_session, make_user, exercise, store):
    patient = make_user("patient")
    session = store(patient, exercise, THURSDAY_NOON - dt.timedelta(days=1))
    db_session.add(SessionFeeling(session_id=session.id, pain_nrs=8, effort_cr10=5.0))
    db_session.flush()
    row = dashboard.summaries(db_session=db_session, patient_ids=[patient.id], now=THURSDAY_NOON)[patient.id]
    reasons = row["attention_reasons"]
    assert row["attention_score"] >= 30 and any(r.startswith("Said pain 8 of 10") for r in reasons), row


def _pain_row(client, db_session, store, exercise, patient, therapist_headers, pain):
    session = store(patient, exercise, THURSDAY_NOON - dt.timedelta(days=1))
    db_session.add(SessionFeeling(session_id=session.id, pain_nrs=pain, effort_cr10=3.0))
    db_session.flush()
    return dashboard.summaries(db_session=db_session, patient_ids=[patient.id], now=THURSDAY_NOON)[patient.id]


def test_the_therapist_sets_the_alert_level_and_the_attention_score_follows_it(
    client, db_session, make_patient_with_therapist, auth_headers, exercise, store
):
    patient, therapist = make_patient_with_therapist()
    headers = auth_headers(therapist)
    assert client.get(f"/api/v1/patients/{patient.id}", headers=headers).json()["pain_alert_above"] == 5
    row = _pain_row(client, db_session, store, exercise, patient, headers, pain=4)
    assert row["attention_score"] == 0 and row["attention_reasons"] == [], row
    r = client.patch(f"/api/v1/patients/{patient.id}", json={"pain_alert_above": 3}, headers=headers)
    assert r.status_code == 200, r.text
    assert r.json()["pain_alert_above"] == 3 and r.json()["locale"] is None  # the language was left alone
    summary = client.get(f"/api/v1/patients/{patient.id}/summary", headers=headers).json()
    assert summary["attention_level"] == "soon", summary
    assert any(r.startswith("Said pain 4 of 10") and r.endswith("(alert above 3)") for r in
               summary["attention_reasons"]), summary["attention_reasons"]  # fmt: skip
    back = client.patch(f"/api/v1/patients/{patient.id}", json={"pain_alert_above": None}, headers=headers)
    assert back.json()["pain_alert_above"] == 5


@pytest.mark.parametrize("bad", [10, -1, 4.5, "high"])
def test_an_alert_level_outside_0_to_9_is_refused(client, make_patient_with_therapist, auth_headers, bad):
    patient, therapist = make_patient_with_therapist()
    r = client.patch(f"/api/v1/patients/{patient.id}", json={"pain_alert_above": bad}, headers=auth_headers(therapist))
    assert r.status_code == 422 and r.json()["error"] == "ValidationError", r.text
    assert "pain_alert_above" in r.json()["detail"], r.text


def test_the_patient_changes_their_language_but_not_their_alert_level(client, make_user, auth_headers):
    patient = make_user("patient")
    mine = auth_headers(patient)
    r = client.patch(f"/api/v1/patients/{patient.id}", json={"locale": "de"}, headers=mine)
    assert r.status_code == 200 and r.json()["pain_alert_above"] == 5, r.text
    r = client.patch(f"/api/v1/patients/{patient.id}", json={"pain_alert_above": 9}, headers=mine)
    assert r.status_code == 403 and "therapist" in r.json()["detail"], r.text


# --- "It hurt" answered to advice -----------------------------------------------------------------------------


def test_an_unread_it_hurt_reply_makes_the_patient_soon_with_the_day():
    found = _attention([_at(3, 2)], unread_hurt=1, last_hurt_at=THURSDAY_NOON - dt.timedelta(hours=3))
    assert found.score == 30 and found.level == "soon", found
    assert found.reasons == ["Answered advice “It hurt” on 26 Nov (unread)"], found.reasons
    two = _attention([], unread_hurt=2, last_hurt_at=THURSDAY_NOON - dt.timedelta(days=2))
    assert two.score == 30 and two.reasons == ["2 unread “It hurt” answers to advice, the latest on 24 Nov"]
    assert _attention([_at(3, 2)], unread_hurt=0, last_hurt_at=None).score == 0


def test_it_hurt_adds_to_high_pain():
    found = _attention([_at(1, 7)], unread_hurt=1, last_hurt_at=THURSDAY_NOON)
    assert found.score == 60 and found.level == "now", found
    assert len(found.reasons) == 2 and any("It hurt" in r for r in found.reasons), found.reasons


def _dashboard_row(client, headers, patient_id: int) -> dict[str, Any]:
    r = client.get("/api/v1/dashboard", headers=headers)
    assert r.status_code == 200, r.text
    return next(row for row in r.json()["items"] if row["patient_id"] == patient_id)


@pytest.mark.parametrize("preset", ["hurt", "done"])
def test_the_dashboard_raises_an_unread_it_hurt_until_it_is_read(client, make_patient_with_therapist, auth_headers,
                                                                 preset):  # fmt: skip
    patient, therapist = make_patient_with_therapist()
    theirs, mine = auth_headers(therapist), auth_headers(patient)
    advice = client.post(f"/api/v1/patients/{patient.id}/suggestions", json={"text": "Deeper squats."}, headers=theirs)
    before = _dashboard_row(client, theirs, patient.id)
    reply = client.post(f"/api/v1/patients/{patient.id}/replies", json={"suggestion_id": advice.json()["id"],
                                                                      "preset": preset}, headers=mine)  # fmt: skip
    assert reply.status_code == 201, reply.text
    unread = _dashboard_row(client, theirs, patient.id)
    hurt = [r for r in unread["attention_reasons"] if "It hurt" in r]
    if preset == "done":  # only "It hurt" is a sign about the patient
        assert unread["attention_score"] == before["attention_score"] and not hurt, unread
        return
    assert unread["attention_score"] == before["attention_score"] + 30, (before, unread)
    assert unread["attention_level"] != "ok" and hurt and hurt[0].startswith("Answered advice “It hurt” on "), unread
    r = client.post(f"/api/v1/patients/{patient.id}/replies/read", json={"reply_ids": [reply.json()["id"]]},
                    headers=theirs)  # fmt: skip
    assert r.status_code == 200 and r.json()["marked"] == 1, r.text
    read = _dashboard_row(client, theirs, patient.id)
    assert read["attention_score"] == before["attention_score"], read
    assert not [r for r in read["attention_reasons"] if "It hurt" in r], read


def test_the_dashboard_puts_the_patient_who_said_it_hurt_first(client, make_user, auth_headers, db_session):
    from backend.database import utcnow
    from backend.patients.models import TherapistPatient

    therapist = make_user("therapist")
    patient, other = make_user("patient", full_name="Zoe Zed"), make_user("patient", full_name="Anna Able")
    for p in (patient, other):
        db_session.add(TherapistPatient(therapist_id=therapist.id, patient_id=p.id, created_at=utcnow()))
    db_session.flush()
    theirs = auth_headers(therapist)
    advice = client.post(f"/api/v1/patients/{patient.id}/suggestions", json={"text": "Slower."}, headers=theirs)
    names = [row["full_name"] for row in client.get("/api/v1/dashboard", headers=theirs).json()["items"]]
    assert names == ["Anna Able", "Zoe Zed"], names  # equal scores: by name
    r = client.post(f"/api/v1/patients/{patient.id}/replies", json={"suggestion_id": advice.json()["id"],
                    "preset": "hurt"}, headers=auth_headers(patient))  # fmt: skip
    assert r.status_code == 201, r.text
    names = [row["full_name"] for row in client.get("/api/v1/dashboard", headers=theirs).json()["items"]]
    assert names == ["Zoe Zed", "Anna Able"], names
