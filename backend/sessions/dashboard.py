"""Per-patient views over stored sessions: progress series and the therapist dashboard summary.

Summaries of many patients cost a fixed number of queries (no query per patient), read the indexed scalar columns
of session_metric and only the "indicators" part of a document, and never load the stored files.
"""

from __future__ import annotations

import datetime as dt
from collections.abc import Sequence

from sqlalchemy import func, or_, select
from sqlalchemy.orm import Session

from backend.exercises.models import Exercise
from backend.plans.models import Plan, PlanItem
from backend.sessions.models import ExerciseSession, SessionMetric
from backend.suggestions.models import Suggestion


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


def _last_sessions(db_session: Session, patient_ids: Sequence[int]) -> dict[int, dict]:
    """Returns the newest session of each patient that has one (brief fields)."""
    ranked = (
        select(
            ExerciseSession.id,
            ExerciseSession.patient_id,
            func.row_number()
            .over(
                partition_by=ExerciseSession.patient_id,
                order_by=(ExerciseSession.started_at.desc(), ExerciseSession.id.desc()),
            )
            .label("rank"),
        )
        .where(ExerciseSession.patient_id.in_(patient_ids))
        .subquery()
    )
    rows = db_session.execute(
        select(
            ExerciseSession.patient_id,
            ExerciseSession.id,
            Exercise.slug,
            ExerciseSession.started_at,
            SessionMetric.repetitions,
            SessionMetric.rom_deg,
            SessionMetric.quality_ok,
        )
        .join(ranked, (ranked.c.id == ExerciseSession.id) & (ranked.c.rank == 1))
        .outerjoin(Exercise, Exercise.id == ExerciseSession.exercise_id)
        .outerjoin(SessionMetric, SessionMetric.session_id == ExerciseSession.id)
    ).all()
    keys = ("id", "exercise_slug", "started_at", "repetitions", "rom_deg", "quality_ok")
    return {row[0]: dict(zip(keys, row[1:], strict=True)) for row in rows}


def _latest_indicators(db_session: Session, patient_ids: Sequence[int]) -> dict[int, dict]:
    """Returns the indicators of each patient's newest session that has metrics."""
    ranked = (
        select(
            SessionMetric.id,
            ExerciseSession.patient_id,
            func.row_number()
            .over(
                partition_by=ExerciseSession.patient_id,
                order_by=(ExerciseSession.started_at.desc(), ExerciseSession.id.desc()),
            )
            .label("rank"),
        )
        .join(ExerciseSession, ExerciseSession.id == SessionMetric.session_id)
        .where(ExerciseSession.patient_id.in_(patient_ids))
        .subquery()
    )
    rows = db_session.execute(
        select(ranked.c.patient_id, SessionMetric.document["indicators"])
        .join(ranked, ranked.c.id == SessionMetric.id)
        .where(ranked.c.rank == 1)
    ).all()
    return {pid: indicators for pid, indicators in rows if isinstance(indicators, dict)}


def _count_by_patient(db_session: Session, column, *conditions) -> dict[int, int]:
    rows = db_session.execute(select(column, func.count()).where(*conditions).group_by(column)).all()
    return {pid: n for pid, n in rows}


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
    """Returns the dashboard summary of each patient (SummaryOut fields) in six queries, whatever their number."""
    ids = sorted(set(patient_ids))
    if not ids:
        return {}
    last = _last_sessions(db_session, ids)
    indicators = _latest_indicators(db_session, ids)
    this_week = _count_by_patient(
        db_session,
        ExerciseSession.patient_id,
        ExerciseSession.patient_id.in_(ids),
        ExerciseSession.started_at >= week_start(now),
    )
    pending = _count_by_patient(
        db_session,
        Suggestion.patient_id,
        Suggestion.patient_id.in_(ids),
        Suggestion.source == "system",
        Suggestion.status == "pending",
    )
    planned = _planned_per_week(db_session, ids, now.astimezone(dt.UTC).date())
    return {
        pid: {
            "patient_id": pid,
            "last_session": last.get(pid),
            "sessions_this_week": this_week.get(pid, 0),
            "planned_this_week": planned.get(pid),
            "latest_indicators": indicators.get(pid),
            "pending_suggestions": pending.get(pid, 0),
        }
        for pid in ids
    }
