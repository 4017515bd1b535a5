"""Reply queries and changes: store a patient's reply, list replies with the advice they answer, mark them read."""

from __future__ import annotations

from typing import Any, cast

from sqlalchemy import Select, func, select, update
from sqlalchemy.engine import CursorResult
from sqlalchemy.orm import Session

from backend.database import utcnow
from backend.exceptions import ReplyNotFound
from backend.i18n import Translator
from backend.replies.models import AdviceReply
from backend.replies.schemas import ReplyIn, ReplyOut
from backend.suggestions import service as suggestions
from backend.suggestions.models import Suggestion


def add_reply(*, db_session: Session, patient_id: int, body: ReplyIn, accept_language: str | None = None) -> ReplyOut:
    """Stores the patient's reply to one of their visible pieces of advice (flushed, not committed).

    Raises SuggestionNotFound when the advice does not exist, is another patient's, or the patient cannot see it
    (a system suggestion not approved), so a patient cannot tell those apart.
    """
    advice = db_session.get(Suggestion, body.suggestion_id)
    if advice is None or advice.patient_id != patient_id or not suggestions.is_visible_to_patient(advice):
        raise suggestions.missing(body.suggestion_id)
    row = AdviceReply(suggestion_id=advice.id, patient_id=patient_id, preset=body.preset, text=body.text)
    db_session.add(row)
    db_session.flush()
    return _out(row, _advice_text(db_session, advice, accept_language, {}))


def list_replies(
    *,
    db_session: Session,
    patients: Select[int] | list[int] | None,
    unread: bool | None,
    suggestion_id: int | None = None,
    limit: int,
    offset: int,
    accept_language: str | None = None,
) -> tuple[list[ReplyOut], int]:
    """Returns one page of replies (newest first) and the total; patients: a select of patient ids, or None (all).
    The advice each answers is in the request's language (accept_language; suggestions.service.reader)."""
    query = select(AdviceReply, Suggestion).join(Suggestion, Suggestion.id == AdviceReply.suggestion_id)
    if patients is not None:
        query = query.where(AdviceReply.patient_id.in_(patients))
    if unread is not None:
        query = query.where(AdviceReply.read_at.is_(None) if unread else AdviceReply.read_at.is_not(None))
    if suggestion_id is not None:
        query = query.where(AdviceReply.suggestion_id == suggestion_id)
    total = db_session.scalar(select(func.count()).select_from(query.subquery())) or 0
    rows = db_session.execute(
        query.order_by(AdviceReply.created_at.desc(), AdviceReply.id.desc()).limit(limit).offset(offset)
    ).all()
    readers: dict[int, Translator] = {}
    return [_out(reply, _advice_text(db_session, advice, accept_language, readers)) for reply, advice in rows], total


def _advice_text(db_session: Session, advice: Suggestion, accept_language: str | None,
                 readers: dict[int, Translator]) -> str:  # fmt: skip
    """Returns the advice's text in its reader's language; readers: the language found per patient so far."""
    if advice.patient_id not in readers:
        readers[advice.patient_id] = suggestions.reader(accept_language, db_session=db_session,
                                                        patient_id=advice.patient_id)  # fmt: skip
    return suggestions.shown_text(advice, readers[advice.patient_id])[0]


def mark_read(*, db_session: Session, patient_id: int, reply_ids: list[int], reader_id: int) -> int:
    """Marks these replies of the patient read by reader_id; returns how many were unread.

    Raises ReplyNotFound when an id is not a reply of this patient. Replies already read keep their first reader.
    """
    ids = sorted(set(reply_ids))
    known = set(
        db_session.scalars(select(AdviceReply.id).where(AdviceReply.id.in_(ids), AdviceReply.patient_id == patient_id))
    )
    unknown = [i for i in ids if i not in known]
    if unknown:
        raise ReplyNotFound(f"reply {unknown[0]} does not exist")
    result = db_session.execute(
        update(AdviceReply)
        .where(AdviceReply.id.in_(ids), AdviceReply.read_at.is_(None))
        .values(read_at=utcnow(), read_by_id=reader_id)
        .execution_options(synchronize_session="fetch")
    )
    return int(cast("CursorResult[Any]", result).rowcount or 0)  # an UPDATE's result is a CursorResult


def _out(row: AdviceReply, advice_text: str) -> ReplyOut:
    return ReplyOut(
        id=row.id,
        patient_id=row.patient_id,
        suggestion_id=row.suggestion_id,
        suggestion_text=advice_text,
        preset=row.preset,  # the table's check constraint keeps it one of PRESETS
        text=row.text,
        created_at=row.created_at,
        read_at=row.read_at,
        read_by_id=row.read_by_id,
    )
