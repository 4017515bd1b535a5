"""The pain a patient says after a set (0-10, backend.feeling) raises their attention score with the reason in
words: high pain at once, a rising median over the weeks (backend.sessions.triage, module doc "pain")."""

from __future__ import annotations

import datetime as dt

import pytest

from backend.feeling.models import SessionFeeling
from backend.sessions import dashboard
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
