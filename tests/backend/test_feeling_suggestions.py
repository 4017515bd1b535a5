"""The pain a patient says after a set feeds the suggestion rules (backend.suggestions.rules pain_high, pain_rising):
advice for the therapist to review, in the patient's language, with the check it rests on."""

from __future__ import annotations

import datetime as dt

from backend.database import utcnow
from backend.feeling.models import SessionFeeling
from backend.suggestions import rules
from backend.suggestions.models import Suggestion


def _answer(client, headers, session_id: int, pain, effort=3.0):
    r = client.put(f"/api/v1/sessions/{session_id}/feeling", json={"pain": pain, "effort": effort}, headers=headers)
    assert r.status_code == 200, r.text


def _system(db_session, patient_id: int) -> list[Suggestion]:
    return list(db_session.query(Suggestion).filter_by(patient_id=patient_id, source="system").order_by(Suggestion.id))


def test_pain_above_the_alert_level_makes_advice_for_the_therapist_to_review(
    client, db_session, make_patient_with_therapist, auth_headers, exercise, store
):
    patient, therapist = make_patient_with_therapist()
    session = store(patient, exercise, utcnow() - dt.timedelta(hours=1))
    _answer(client, auth_headers(patient), session.id, 7)
    found = _system(db_session, patient.id)
    assert [(s.rule, s.status, s.session_id) for s in found] == [("pain_high", "pending", session.id)]
    assert (found[0].metric, found[0].comparison, found[0].threshold, found[0].value) == ("pain_nrs", ">", 5.0, 7.0)
    assert "your pain was 7 of 10" in found[0].text and "tell your therapist" in found[0].text, found[0].text
    pending = client.get(f"/api/v1/patients/{patient.id}/suggestions", params={"status": "pending"},
                         headers=auth_headers(therapist)).json()["items"]  # fmt: skip
    assert [s["rule"] for s in pending] == ["pain_high"]


def test_pain_at_or_below_the_alert_level_or_skipped_makes_none(
    client, db_session, make_user, auth_headers, exercise, store
):
    patient = make_user("patient")
    headers = auth_headers(patient)
    for hours, pain in ((3, 5), (2, None), (1, 0)):
        _answer(client, headers, store(patient, exercise, utcnow() - dt.timedelta(hours=hours)).id, pain)
    assert _system(db_session, patient.id) == []


def test_the_therapists_alert_level_moves_the_rule(
    client, db_session, make_patient_with_therapist, auth_headers, exercise, store
):
    patient, therapist = make_patient_with_therapist()
    theirs, mine = auth_headers(therapist), auth_headers(patient)
    assert client.patch(f"/api/v1/patients/{patient.id}", json={"pain_alert_above": 7}, headers=theirs).is_success
    _answer(client, mine, store(patient, exercise, utcnow() - dt.timedelta(hours=2)).id, 7)
    assert _system(db_session, patient.id) == []
    assert client.patch(f"/api/v1/patients/{patient.id}", json={"pain_alert_above": 2}, headers=theirs).is_success
    _answer(client, mine, store(patient, exercise, utcnow() - dt.timedelta(hours=1)).id, 3)
    assert [(s.rule, s.threshold, s.value) for s in _system(db_session, patient.id)] == [("pain_high", 2.0, 3.0)]


def test_pain_rising_over_the_week_is_said_with_both_medians_in_the_patients_language(
    client, db_session, make_user, auth_headers, exercise, store
):
    patient = make_user("patient")
    headers = auth_headers(patient)
    assert client.patch(f"/api/v1/patients/{patient.id}", json={"locale": "de"}, headers=headers).is_success
    now = utcnow()
    for days, pain in ((20, 1), (12, 1), (3, 4)):
        earlier = store(patient, exercise, now - dt.timedelta(days=days))
        db_session.add(SessionFeeling(session_id=earlier.id, pain_nrs=pain, effort_cr10=2.0))
    db_session.flush()
    _answer(client, headers, store(patient, exercise, now - dt.timedelta(hours=1)).id, 4)
    found = _system(db_session, patient.id)
    assert [(s.rule, s.metric, s.threshold, s.value) for s in found] == [
        ("pain_rising", "pain_nrs_median_7d", 3.0, 4.0)
    ], found  # fmt: skip
    assert "etwa 4 von 10" in found[0].text and "etwa 1 von 10" in found[0].text, found[0].text


def test_pain_rising_needs_two_answers_before_the_week_and_a_rise_of_two_points():
    now = dt.datetime(2026, 11, 26, 12, tzinfo=dt.UTC)
    at = lambda days, pain: (now - dt.timedelta(days=days), pain)  # noqa: E731
    assert rules.pain_rising([at(20, 1), at(1, 6)], now) is None  # one answer before the week
    assert rules.pain_rising([at(20, 2), at(10, 3), at(1, 4)], now) is None  # 2.5 -> 4: a rise of 1.5
    fired = rules.pain_rising([at(20, 2), at(10, 3), at(1, 5)], now)
    assert fired is not None and (fired.threshold, fired.value) == (4.5, 5.0)
    assert "about 5 of 10" in fired.text and "about 2.5 of 10" in fired.text, fired.text


def test_a_corrected_answer_withdraws_pain_advice_that_no_longer_holds(
    client, db_session, make_user, auth_headers, exercise, store
):
    patient = make_user("patient")
    headers = auth_headers(patient)
    session = store(patient, exercise, utcnow() - dt.timedelta(hours=1))
    _answer(client, headers, session.id, 8)
    _answer(client, headers, session.id, 2)  # the patient pressed 8 by mistake
    db_session.expire_all()
    assert [(s.rule, s.status) for s in _system(db_session, patient.id)] == [("pain_high", "superseded")]
    _answer(client, headers, session.id, 9)  # high again: the same advice comes back, with the new number
    db_session.expire_all()
    found = _system(db_session, patient.id)
    assert [(s.rule, s.status, s.value) for s in found] == [("pain_high", "pending", 9.0)]
    assert "your pain was 9 of 10" in found[0].text, found[0].text
