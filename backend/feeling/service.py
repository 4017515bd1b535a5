"""Reads and stores how a set felt (queries only; the router checks access and audits)."""

from __future__ import annotations

from sqlalchemy.orm import Session

from backend.feeling.models import SessionFeeling
from backend.feeling.schemas import FeelingIn, FeelingOut


def _out(session_id: int, row: SessionFeeling | None) -> FeelingOut:
    if row is None:
        return FeelingOut(session_id=session_id, pain=None, effort=None, answered_at=None)
    return FeelingOut(session_id=session_id, pain=row.pain_nrs, effort=row.effort_cr10, answered_at=row.updated_at)


def get_feeling(*, db_session: Session, session_id: int) -> FeelingOut:
    """Returns how the set felt (nulls when the patient has not answered)."""
    return _out(session_id, db_session.get(SessionFeeling, session_id))


def set_feeling(*, db_session: Session, session_id: int, body: FeelingIn) -> FeelingOut:
    """Stores the patient's answers for a session; returns them."""
    row = db_session.get(SessionFeeling, session_id)
    if row is None:
        row = SessionFeeling(session_id=session_id)
        db_session.add(row)
    row.pain_nrs, row.effort_cr10 = body.pain, body.effort
    db_session.flush()
    return _out(session_id, row)
