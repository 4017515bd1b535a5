"""What the analysis and the suggestion rules need to know around one session: the plan's targets and the patient's
earlier sessions."""

from __future__ import annotations

import datetime as dt
from typing import Any

from sqlalchemy import Select, or_, select
from sqlalchemy.orm import Session

from backend.plans.models import Plan, PlanItem
from backend.sessions.models import ExerciseSession, SessionMetric
from kinect_agent.analysis.document import AnalysisReport, read_if_readable

HISTORY_WINDOW_DAYS = 28  # the history's look-back: the suggestion rules' longest window (their ROM baseline)


def plan_targets(
    *, db_session: Session, patient_id: int, exercise_id: int | None, on: dt.date
) -> tuple[int | None, int | None]:
    """Returns (repetitions, frequency_per_week) the patient's plan prescribes for the exercise on a day.

    The plan must be running on that day (start_date <= on <= end_date, open end allowed); when several are, the
    one that started last wins. (None, None) when no plan prescribes the exercise.
    """
    if exercise_id is None:
        return None, None
    item = db_session.scalars(
        select(PlanItem)
        .join(Plan, Plan.id == PlanItem.plan_id)
        .where(
            Plan.patient_id == patient_id,
            PlanItem.exercise_id == exercise_id,
            Plan.start_date <= on,
            or_(Plan.end_date.is_(None), Plan.end_date >= on),
        )
        .order_by(Plan.start_date.desc(), Plan.id.desc(), PlanItem.position)
        .limit(1)
    ).first()
    return (item.repetitions, item.frequency_per_week) if item is not None else (None, None)


def _earlier(session: ExerciseSession) -> Select[dt.datetime, dict[str, Any] | None]:
    return (
        select(ExerciseSession.started_at, SessionMetric.document)
        .join(SessionMetric, SessionMetric.session_id == ExerciseSession.id)
        .where(
            ExerciseSession.patient_id == session.patient_id,
            ExerciseSession.exercise_id == session.exercise_id,
            ExerciseSession.id != session.id,
            ExerciseSession.started_at <= session.started_at,
        )
    )


def session_history(
    *, db_session: Session, session: ExerciseSession
) -> list[tuple[dt.datetime, AnalysisReport | None]]:
    """Returns (started_at, metrics document) of the patient's earlier sessions of the same exercise, oldest first;
    the document read from whatever schema version it was stored in, None where no schema reads it (the session
    still happened: the missed-days rule counts its day).

    Covers HISTORY_WINDOW_DAYS (the rules' longest window) plus the latest session before it, so the
    missed-days rule can tell a returning patient from a new one.
    """
    start = session.started_at - dt.timedelta(days=HISTORY_WINDOW_DAYS)
    recent = db_session.execute(_earlier(session).where(ExerciseSession.started_at >= start)).all()
    older = db_session.execute(
        _earlier(session).where(ExerciseSession.started_at < start).order_by(ExerciseSession.started_at.desc()).limit(1)
    ).all()
    rows: list[tuple[dt.datetime, AnalysisReport | None]] = [(t, read_if_readable(doc)) for t, doc in [*older, *recent]]
    return sorted(rows, key=lambda row: row[0])
