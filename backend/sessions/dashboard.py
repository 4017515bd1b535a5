"""Per-patient views over stored sessions: progress series and the therapist dashboard summary.

Summaries of many patients cost two queries (no query per patient), read the indexed scalar columns
of session_metric and only the "indicators" part of a document, and never load the stored files.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Sequence

from sqlalchemy import func, or_, select
from sqlalchemy.orm import Session, aliased

from backend.exercises.models import Exercise
from backend.plans.models import Plan, PlanItem
from backend.sessions.models import ExerciseSession, SessionMetric
from backend.suggestions.models import Suggestion
from backend.users.models import User


def week_start(now: dt.datetime) -> dt.datetime:
    """Returns Monday 00:00 UTC of the week that contains now (timezone-aware)."""
    day = now.astimezone(dt.UTC).date()
    monday = day - dt.timedelta(days=day.weekday())
    return dt.datetime.combine(monday, dt.time(), tzinfo=dt.UTC)


def progress(*, db_session: Session, patient_id: int, exercise_id: int | None, since: dt.datetime | None) -> list[dict]:
    """Returns one point per session of the patient (optionally one exercise, since a time), oldest first.

    Each point: session_id, exercise_slug, started_at, repetitions, rom_deg (deg), quality_ok, indicators.
    """
    query = (
        select(
            ExerciseSession.id,
            Exercise.slug,
            ExerciseSession.started_at,
            SessionMetric.repetitions,
            SessionMetric.rom_deg,
            SessionMetric.quality_ok,
            SessionMetric.document["indicators"],
        )
        .select_from(ExerciseSession)
        .outerjoin(Exercise, Exercise.id == ExerciseSession.exercise_id)
        .outerjoin(SessionMetric, SessionMetric.session_id == ExerciseSession.id)
        .where(ExerciseSession.patient_id == patient_id)
    )
    if exercise_id is not None:
        query = query.where(ExerciseSession.exercise_id == exercise_id)
    if since is not None:
        query = query.where(ExerciseSession.started_at >= since)
    rows = db_session.execute(query.order_by(ExerciseSession.started_at, ExerciseSession.id)).all()
    keys = ("session_id", "exercise_slug", "started_at", "repetitions", "rom_deg", "quality_ok", "indicators")
    return [dict(zip(keys, row, strict=True)) for row in rows]


def _newest_session(*, with_metrics: bool):
    """Returns a scalar subquery correlated to User: the patient's newest session id (with metrics, if asked).

    ORDER BY started_at DESC, id DESC LIMIT 1 walks the (patient_id, started_at, id) index backwards from the newest
    row, so the cost does not grow with the patient's number of sessions.
    """
    newest = select(ExerciseSession.id).where(ExerciseSession.patient_id == User.id)
    if with_metrics:
        newest = newest.join(SessionMetric, SessionMetric.session_id == ExerciseSession.id)
    return (
        newest.order_by(ExerciseSession.started_at.desc(), ExerciseSession.id.desc())
        .limit(1)
        .correlate(User)
        .scalar_subquery()
    )


def _per_patient(db_session: Session, patient_ids: Sequence[int], now: dt.datetime) -> dict[int, dict]:
    """Returns per patient (one query): last session (brief), latest indicators, sessions this week, pending advice."""
    this_week = (
        select(func.count())
        .select_from(ExerciseSession)
        .where(ExerciseSession.patient_id == User.id, ExerciseSession.started_at >= week_start(now))
        .correlate(User)
        .scalar_subquery()
    )
    pending = (
        select(func.count())
        .select_from(Suggestion)
        .where(Suggestion.patient_id == User.id, Suggestion.source == "system", Suggestion.status == "pending")
        .correlate(User)
        .scalar_subquery()
    )
    per = (
        select(
            User.id.label("pid"),
            _newest_session(with_metrics=False).label("sid"),
            _newest_session(with_metrics=True).label("mid"),
            this_week.label("this_week"),
            pending.label("pending"),
        )
        .where(User.id.in_(patient_ids))
        .subquery()
    )
    last_metric, indicator_metric = aliased(SessionMetric), aliased(SessionMetric)
    rows = db_session.execute(
        select(
            per.c.pid,
            per.c.this_week,
            per.c.pending,
            ExerciseSession.id,
            Exercise.slug,
            ExerciseSession.started_at,
            last_metric.repetitions,
            last_metric.rom_deg,
            last_metric.quality_ok,
            indicator_metric.document["indicators"],
        )
        .select_from(per)
        .outerjoin(ExerciseSession, ExerciseSession.id == per.c.sid)
        .outerjoin(Exercise, Exercise.id == ExerciseSession.exercise_id)
        .outerjoin(last_metric, last_metric.session_id == per.c.sid)
        .outerjoin(indicator_metric, indicator_metric.session_id == per.c.mid)
    ).all()
    keys = ("id", "exercise_slug", "started_at", "repetitions", "rom_deg", "quality_ok")
    return {
        pid: {
            "last_session": dict(zip(keys, last, strict=True)) if last[0] is not None else None,
            "sessions_this_week": this_week or 0,
            "pending_suggestions": pending or 0,
            "latest_indicators": indicators if isinstance(indicators, dict) else None,
        }
        for pid, this_week, pending, *last, indicators in rows
    }


def _planned_per_week(db_session: Session, patient_ids: Sequence[int], on: dt.date) -> dict[int, int]:
    """Returns sessions per week the running plans prescribe: per exercise the newest plan's frequency, summed."""
    rows = db_session.execute(
        select(Plan.patient_id, PlanItem.exercise_id, PlanItem.frequency_per_week)
        .join(Plan, Plan.id == PlanItem.plan_id)
        .where(
            Plan.patient_id.in_(patient_ids),
            Plan.start_date <= on,
            or_(Plan.end_date.is_(None), Plan.end_date >= on),
        )
        .order_by(Plan.start_date.desc(), Plan.id.desc(), PlanItem.position)
    ).all()
    chosen: dict[tuple[int, int], int] = {}
    for pid, exercise_id, per_week in rows:
        chosen.setdefault((pid, exercise_id), per_week)
    planned: dict[int, int] = {}
    for (pid, _), per_week in chosen.items():
        planned[pid] = planned.get(pid, 0) + per_week
    return planned


def summaries(*, db_session: Session, patient_ids: Sequence[int], now: dt.datetime) -> dict[int, dict]:
    """Returns the dashboard summary of each patient (SummaryOut fields) in two queries, whatever their number."""
    ids = sorted(set(patient_ids))
    if not ids:
        return {}
    per = _per_patient(db_session, ids, now)
    planned = _planned_per_week(db_session, ids, now.astimezone(dt.UTC).date())
    empty = {"last_session": None, "sessions_this_week": 0, "pending_suggestions": 0, "latest_indicators": None}
    return {pid: {"patient_id": pid, **empty, **per.get(pid, {}), "planned_this_week": planned.get(pid)} for pid in ids}
