"""Rules on stored sessions: plan targets, the patient's history, and missed days judged once a week."""

from __future__ import annotations

import datetime as dt
import uuid

import pytest
from sqlalchemy import select

from backend.plans.models import Plan, PlanItem
from backend.sessions.history import plan_targets, session_history
from backend.sessions.models import ExerciseSession, SessionMetric
from backend.suggestions.models import Suggestion
from backend.suggestions.service import suggest_for_session
from kinect_agent.analysis.document import AnalysisReport, read_report
from tests.backend.session_rows import report

NOW = dt.datetime(2026, 11, 23, 10, 0, tzinfo=dt.UTC)
TODAY = NOW.date()


def _doc(slug: str, **overrides) -> AnalysisReport:
    good = {
        "exercise": slug,
        "repetitions": 10,
        "rom_deg": 80.0,
        "tempo_s_per_rep": 3.0,
        "quality": {"ok": True, "tracked_fraction": 1.0, "outlier_fraction": 0.0, "reasons": []},
    }
    return report(**(good | overrides))


@pytest.fixture
def store(db_session):
    """Factory: store(patient, exercise, days_ago, doc=None, **doc overrides) -> ExerciseSession with metrics."""

    def make(patient, exercise, days_ago: float, doc: AnalysisReport | None = None, **overrides) -> ExerciseSession:
        doc = doc or _doc(exercise.slug, **overrides)
        row = ExerciseSession(
            client_session_id=uuid.uuid4(),
            patient_id=patient.id,
            exercise_id=exercise.id,
            started_at=NOW - dt.timedelta(days=days_ago),
            duration_s=30.0,
            n_frames=900,
            file_bytes=b"",
            content_hash=uuid.uuid4().hex * 2,
        )
        row.metric = SessionMetric(document=doc.model_dump(mode="json"), repetitions=doc.repetitions,
                                   rom_deg=doc.rom_deg)  # fmt: skip
        db_session.add(row)
        db_session.flush()
        return row

    return make


@pytest.fixture
def plan(db_session, exercise):
    """Factory: plan(patient, start_days_ago, end_days_ahead=None, reps=10, per_week=3) -> Plan of the exercise."""

    def make(patient, start_days_ago=30, end_days_ahead=None, reps=10, per_week=3) -> Plan:
        row = Plan(
            patient_id=patient.id,
            title="p",
            start_date=TODAY - dt.timedelta(days=start_days_ago),
            end_date=None if end_days_ahead is None else TODAY + dt.timedelta(days=end_days_ahead),
        )
        row.items = [PlanItem(exercise_id=exercise.id, sets=1, repetitions=reps, frequency_per_week=per_week)]
        db_session.add(row)
        db_session.flush()
        return row

    return make


def _targets(db_session, patient, exercise):
    return plan_targets(db_session=db_session, patient_id=patient.id, exercise_id=exercise.id, on=TODAY)


# --- plan targets ---


def test_plan_targets_of_a_running_plan(db_session, make_user, exercise, plan):
    patient = make_user("patient")
    plan(patient, reps=12, per_week=4)
    assert _targets(db_session, patient, exercise) == (12, 4)


def test_plan_targets_newest_running_plan_wins(db_session, make_user, exercise, plan):
    patient = make_user("patient")
    plan(patient, start_days_ago=30, reps=12)
    plan(patient, start_days_ago=5, reps=8)
    assert _targets(db_session, patient, exercise) == (8, 3)


@pytest.mark.parametrize(("start", "end"), [(30, -1), (-1, None)])
def test_plan_targets_none_outside_the_plan_dates(db_session, make_user, exercise, plan, start, end):
    patient = make_user("patient")
    plan(patient, start_days_ago=start, end_days_ahead=end)
    assert _targets(db_session, patient, exercise) == (None, None)


def test_plan_targets_end_day_is_included(db_session, make_user, exercise, plan):
    patient = make_user("patient")
    plan(patient, end_days_ahead=0, reps=7)
    assert _targets(db_session, patient, exercise) == (7, 3)


def test_plan_targets_none_for_another_patient(db_session, make_user, exercise, plan):
    plan(make_user("patient"))
    assert _targets(db_session, make_user("patient"), exercise) == (None, None)


# --- history ---


def test_history_is_earlier_sessions_of_the_same_patient_oldest_first(db_session, make_user, exercise, store):
    patient = make_user("patient")
    ancient, old, recent = store(patient, exercise, 60), store(patient, exercise, 40), store(patient, exercise, 3)
    store(patient, exercise, -1)  # later than the current one
    store(make_user("patient"), exercise, 2)  # another patient
    current = store(patient, exercise, 0)
    history = session_history(db_session=db_session, session=current)
    assert [t for t, _ in history] == [old.started_at, recent.started_at], "window plus the latest older one"
    assert ancient.started_at not in [t for t, _ in history]
    assert history[-1][1] is not None and history[-1][1].exercise == exercise.slug


# --- the whole pass ---


def test_suggest_for_session_fires_every_measured_rule(db_session, make_user, exercise, store, plan):
    patient = make_user("patient")
    plan(patient, reps=10, per_week=3)
    for days in (20, 15, 9, 6):
        store(patient, exercise, days, rom_deg=80.0)
    doc = _doc(exercise.slug, repetitions=6, rom_deg=60.0, tempo_s_per_rep=1.0)
    current = store(patient, exercise, 0, doc=doc)
    rows = suggest_for_session(db_session=db_session, session=current, doc=doc)
    got = {r.rule: (r.metric, r.value, r.comparison, r.threshold, r.status, r.session_id) for r in rows}
    assert got == {
        "fewer_reps": ("repetitions", 6.0, "<", 10.0, "pending", current.id),
        "rom_drop": ("rom_deg", 60.0, "<", pytest.approx(68.0), "pending", current.id),
        "too_fast": ("tempo_s_per_rep", 1.0, "<", 1.5, "pending", current.id),
        "missed_days": ("active_days_last_7d", 2.0, "<", 3.0, "pending", current.id),
    }


def test_suggest_for_session_without_plan_skips_plan_rules(db_session, make_user, exercise, store):
    patient = make_user("patient")
    store(patient, exercise, 10)
    doc = _doc(exercise.slug, repetitions=1)
    rows = suggest_for_session(db_session=db_session, session=store(patient, exercise, 0, doc=doc), doc=doc)
    assert rows == []


def test_missed_days_is_suggested_once_a_week(db_session, make_user, exercise, store, plan):
    patient = make_user("patient")
    plan(patient, per_week=5)
    store(patient, exercise, 12)
    doc = _doc(exercise.slug)
    first = suggest_for_session(db_session=db_session, session=store(patient, exercise, 3, doc=doc), doc=doc)
    second = suggest_for_session(db_session=db_session, session=store(patient, exercise, 0, doc=doc), doc=doc)
    later = suggest_for_session(db_session=db_session, session=store(patient, exercise, -5, doc=doc), doc=doc)
    assert ([r.rule for r in first], second, [r.rule for r in later]) == (["missed_days"], [], ["missed_days"])


def test_an_earlier_document_no_schema_reads_is_a_session_without_numbers(db_session, make_user, exercise, store):
    patient = make_user("patient")
    broken = store(patient, exercise, 3)
    broken.metric.document = {"exercise": exercise.slug, "rom_deg": "wide"}
    db_session.flush()
    current = store(patient, exercise, 0)
    assert session_history(db_session=db_session, session=current) == [(broken.started_at, None)]


def test_newer_advice_supersedes_pending_advice_of_the_same_rule_and_exercise(
    db_session, make_user, exercise, other_exercise, store
):
    patient = make_user("patient")
    fired = {}
    for days, ex in ((10, exercise), (6, other_exercise), (3, exercise)):
        session = store(patient, ex, days, tempo_s_per_rep=1.0)  # too fast every time
        rows = suggest_for_session(db_session=db_session, session=session, doc=read_report(session.metric.document))
        fired[days] = {r.rule: r for r in rows}
    db_session.refresh(fired[10]["too_fast"])
    assert fired[10]["too_fast"].status == "superseded"  # replaced by the session 3 days ago: same exercise, rule
    assert fired[10]["too_fast"].decided_at is not None and fired[10]["too_fast"].decided_by_id is None
    assert fired[6]["too_fast"].status == "pending"  # another exercise's advice stays
    assert fired[3]["too_fast"].status == "pending"

    late = store(patient, exercise, 20, tempo_s_per_rep=1.0)  # an older session uploaded late
    rows = suggest_for_session(db_session=db_session, session=late, doc=read_report(late.metric.document))
    db_session.refresh(fired[3]["too_fast"])
    assert fired[3]["too_fast"].status == "pending"  # never replaces newer advice
    assert [r.status for r in rows if r.rule == "too_fast"] == ["superseded"]  # born replaced by the newer one


@pytest.mark.parametrize("order", [(9, 5, 1, 7, 3), (1, 3, 5, 7, 9), (5, 9, 1, 3, 7)])
def test_one_pending_suggestion_per_rule_and_exercise_whatever_the_upload_order(
    db_session, make_user, exercise, other_exercise, store, plan, order
):
    patient = make_user("patient")
    plan(patient, reps=10, per_week=1)
    sessions = {}
    for days in order:  # uploaded in this order; each one too short and too fast, for both exercises
        for ex in (exercise, other_exercise):
            session = store(patient, ex, days, repetitions=4, tempo_s_per_rep=1.0)
            suggest_for_session(db_session=db_session, session=session, doc=read_report(session.metric.document))
            sessions[session.id] = (ex.slug, days)
    pending = db_session.scalars(
        select(Suggestion).where(Suggestion.patient_id == patient.id, Suggestion.status == "pending")
    ).all()
    got = sorted((sessions[s.session_id][0], s.rule, sessions[s.session_id][1]) for s in pending)
    newest = min(order)
    assert got == sorted(
        [
            (exercise.slug, "fewer_reps", newest),
            (exercise.slug, "too_fast", newest),
            (other_exercise.slug, "too_fast", newest),
        ]  # fmt: skip
    ), "one pending suggestion per rule and exercise, from the newest session"
