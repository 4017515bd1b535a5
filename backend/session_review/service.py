"""Storing an upload with the suggestions its analysis makes, and reading the suggestions about one session."""

from __future__ import annotations

from sqlalchemy import select
from sqlalchemy.orm import Session

from backend.exercises.models import Exercise
from backend.sessions.ingest import Upload
from backend.sessions.models import ExerciseSession
from backend.sessions.service import store_session
from backend.suggestions.models import Suggestion
from backend.suggestions.service import suggest_for_session, visible_to_patient


def store_upload(
    *, db_session: Session, upload: Upload, patient_id: int, exercise: Exercise, device_id: int | None
) -> tuple[ExerciseSession, bool]:
    """Stores an upload with its metrics (sessions.service.store_session) and the system suggestions the rules make
    from a new analysed session; returns (session, created).

    A repeated upload returns the stored session (created=False) and adds nothing. Flushes, never commits: the
    request's transaction keeps the session, metrics and suggestions together.
    """
    row, created, doc = store_session(
        db_session=db_session, upload=upload, patient_id=patient_id, exercise=exercise, device_id=device_id
    )
    if doc is not None:
        suggest_for_session(db_session=db_session, session=row, doc=doc)
    return row, created


def session_suggestions(*, db_session: Session, session_id: int, patient_view: bool) -> list[Suggestion]:
    """Returns the suggestions about one session, oldest first; patient_view keeps only what patients may see."""
    query = select(Suggestion).where(Suggestion.session_id == session_id)
    if patient_view:
        query = query.where(visible_to_patient())
    return list(db_session.scalars(query.order_by(Suggestion.created_at, Suggestion.id)))
