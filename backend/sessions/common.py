"""What the sessions' routes and the routes above them (backend.session_review) share: the exercise query, a list
item's fields, the audit records of session reads, and a stored metrics document read as today's model. Kept out of
backend.sessions.router so that no router imports another one (docs/architecture.md, "Package pairs inside the
server")."""

from __future__ import annotations

import datetime as dt
from collections.abc import Iterable
from typing import Annotated, Any

from fastapi import Query
from pydantic import ValidationError
from sqlalchemy.orm import Session

from backend.audit.service import record, record_patients
from backend.deps import Caller
from backend.exceptions import MetricsUnreadable
from backend.i18n import ENGLISH, Translator
from backend.jobs.listing import error_words
from backend.sessions.models import ExerciseSession
from kinect_agent.analysis.document import AnalysisDocument, UnreadableDocument, read_document

SlugQuery = Annotated[
    str | None, Query(min_length=1, max_length=64, description="exercise slug, e.g. 'squat'", examples=["squat"])
]


def audit(
    db_session: Session,
    caller: Caller,
    action: str,
    session_id: int | None,
    patient_id: int,
    detail: dict[str, Any] | None = None,
) -> None:
    record(
        db_session=db_session,
        caller=caller,
        action=action,
        object_type="exercise_session",
        object_id=session_id,
        patient_id=patient_id,
        detail=detail,
    )


def audit_patients(
    db_session: Session, caller: Caller, action: str, patient_ids: Iterable[int], detail: dict[str, Any] | None = None
) -> None:
    """Adds what audit adds once per patient, in one flush."""
    record_patients(
        db_session=db_session,
        caller=caller,
        action=action,
        object_type="exercise_session",
        patient_ids=patient_ids,
        detail=detail,
    )


def aware(when: dt.datetime | None) -> dt.datetime | None:
    """Returns when with UTC assumed if it carries no time zone."""
    return when.replace(tzinfo=dt.UTC) if when is not None and when.tzinfo is None else when


def stored_metrics(session_id: int, document: dict[str, Any]) -> AnalysisDocument:
    """Returns a session's stored metrics document as today's model; raises MetricsUnreadable naming what no
    schema version reads."""
    try:
        return read_document(document)
    except ValidationError as exc:
        first = exc.errors()[0]
        where = ".".join(str(p) for p in first["loc"])
        raise MetricsUnreadable(
            f"the stored metrics document of session {session_id} cannot be read: {where}: {first['msg']}"
        ) from None
    except UnreadableDocument as exc:
        raise MetricsUnreadable(f"the stored metrics document of session {session_id} cannot be read: {exc}") from None


def item_fields(
    session: ExerciseSession,
    slug: str | None,
    reps: int | None,
    rom: float | None,
    quality: bool | None,
    t: Translator = ENGLISH,
) -> dict[str, Any]:
    """Returns the fields of a session's list item; its failure in t's words (jobs.listing.error_words)."""
    return {
        "id": session.id,
        "client_session_id": session.client_session_id,
        "patient_id": session.patient_id,
        "device_id": session.device_id,
        "exercise_slug": slug,
        "started_at": session.started_at,
        "duration_s": session.duration_s,
        "n_frames": session.n_frames,
        "file_size": session.file_size,
        "content_hash": session.content_hash,
        "status": session.status,
        "error": error_words(session.error, t),
        "repetitions": reps,
        "rom_deg": rom,
        "quality_ok": quality,
        "created_at": session.created_at,
        "file_removed_at": session.file_removed_at,
    }
