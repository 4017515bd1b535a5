"""The pain a patient says after a set (0-10, backend.feeling) raises their attention score with the reason in
words: high pain at once, a rising median over the weeks (backend.sessions.triage, module doc "pain")."""

from __future__ import annotations

import datetime as dt

from backend.feeling.models import SessionFeeling
from backend.sessions import dashboard
from backend.sessions.triage import NOW_AT, SOON_AT, RecentSession, attention

THURSDAY_NOON = dt.datetime(2026, 11, 26, 12, 0, tzinfo=dt.UTC)


def _at(days_ago: float, pain: int | None) -> RecentSession:
    return RecentSession(THURSDAY_NOON - dt.timedelta(days=days_ago), "squat", 10, 90.0, True, None, pain)


def _attention(sessions):
    return attention(now=THURSDAY_NOON, plan=None, sessions_this_week=2, last_session_at=THURSDAY_NOON,
                     sessions=sessions, pending_suggestions=0)  # fmt: skip


def test_high_pain_in_the_last_week_makes_the_patient_soon_with_the_day_and_exercise():
    found = _attention([_at(20, 1), _at(3, 2), _at(1, 7)])
    assert found.score == 30 and found.level == "soon", found
    assert found.reasons == ["Said pain 7 of 10 after Mini squat on 25 Nov"], found.reasons


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
