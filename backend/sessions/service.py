"""Session queries and changes: store an upload idempotently with its metrics, list and read them (the suggestions
made from a stored session: backend.session_review)."""

from __future__ import annotations

import datetime as dt
import uuid
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

from pydantic import ValidationError
from sqlalchemy import ColumnElement, Select, func, select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from backend import __version__
from backend.audit.service import record, record_patients
from backend.database import utcnow
from backend.exceptions import (
    ExerciseNotFound,
    MetricsUnreadable,
    SessionConflict,
    SessionFileRemoved,
    SessionNotFound,
)
from backend.exercises.models import Exercise
from backend.i18n import ENGLISH, Translator
from backend.jobs.listing import error_words
from backend.jobs.models import SessionMetricVersion
from backend.patients.models import TherapistPatient
from backend.patients.service import visible_patients_query
from backend.sessions.history import plan_targets, session_history
from backend.sessions.ingest import Upload
from backend.sessions.metrics import json_ready, metrics_document, scalar_columns
from backend.sessions.models import ExerciseSession, SessionMetric
from backend.storage import get_store
from backend.users.models import User
from kinect_agent.analysis.document import AnalysisDocument, UnreadableDocument, read_document
from kinect_agent.analysis.errors import AnalysisError
from kinect_agent.processing.errors import ProcessingError

if TYPE_CHECKING:
    from backend.deps import Caller

FILE_FORMAT = "khs"


# ---------------------------------------------------------------------------------------------- upload


def find_session(*, db_session: Session, patient_id: int, client_session_id: uuid.UUID) -> ExerciseSession | None:
    """Returns the patient's session with this client session id, or None."""
    return db_session.scalar(
        select(ExerciseSession).where(
            ExerciseSession.patient_id == patient_id, ExerciseSession.client_session_id == client_session_id
        )
    )


def _same_or_conflict(stored: ExerciseSession, upload: Upload, db_session: Session) -> ExerciseSession:
    """Returns the stored session when the upload repeats it byte for byte, or repeats a file a re-analysis replaced
    (the agent's own file, sent again after the pipeline filtered it anew on the server); raises SessionConflict
    otherwise."""
    earlier = select(SessionMetricVersion.id).where(SessionMetricVersion.session_id == stored.id,
                                                    SessionMetricVersion.file_hash == upload.content_hash)  # fmt: skip
    if stored.content_hash != upload.content_hash and db_session.scalar(earlier.limit(1)) is None:
        raise SessionConflict(
            f"session {upload.client_session_id} of patient {stored.patient_id} was already uploaded with different "
            f"content (stored sha256 {stored.content_hash[:16]}..., this upload {upload.content_hash[:16]}...)"
        )
    return stored


def _analyse(
    *, db_session: Session, upload: Upload, patient_id: int, exercise: Exercise
) -> tuple[AnalysisDocument | None, str | None]:
    """Returns (metrics document, None), or (None, reason) when the analysis cannot use the recording."""
    from kinect_agent.analysis.exercise import EXERCISES

    spec = EXERCISES.get(exercise.slug)
    if spec is None:
        raise ExerciseNotFound(f"exercise '{exercise.slug}' is not in the exercise library; it cannot be analysed")
    on = upload.started_at.date()
    target_reps, _ = plan_targets(db_session=db_session, patient_id=patient_id, exercise_id=exercise.id, on=on)
    probe = ExerciseSession(patient_id=patient_id, exercise_id=exercise.id, started_at=upload.started_at)
    history = [doc for _, doc in session_history(db_session=db_session, session=probe) if doc is not None]
    try:
        return metrics_document(upload.payload, spec, target_reps=target_reps, history=history), None
    except AnalysisError as exc:
        return None, f"{type(exc).__name__}: {exc}"
    except ProcessingError as exc:  # not the upload's fault: a 500, nothing stored, the agent keeps the file
        exc.add_note(f"analysing session {upload.client_session_id} of patient {patient_id} ({exercise.slug})")
        raise


def store_session(
    *, db_session: Session, upload: Upload, patient_id: int, exercise: Exercise, device_id: int | None
) -> tuple[ExerciseSession, bool, AnalysisDocument | None]:
    """Stores an upload with its metrics; returns (session, created, metrics document of a new analysed session).

    The same (patient, client session id) with the same content returns the stored session (created=False, no
    document), also when a concurrent request stored it first; with different content raises SessionConflict.
    Flushes, never commits: the request's transaction keeps the session and its metrics together (and what
    backend.session_review.service.store_upload adds from the document: the suggestions).
    """
    with db_session.no_autoflush:  # reads and analysis first; pending writes wait, so no write lock meanwhile
        stored = find_session(db_session=db_session, patient_id=patient_id, client_session_id=upload.client_session_id)
        if stored is not None:
            return _same_or_conflict(stored, upload, db_session), False, None
        doc, error = _analyse(db_session=db_session, upload=upload, patient_id=patient_id, exercise=exercise)
    raw = upload.payload.raw
    stored_file = get_store().put("session", upload.data)  # before the row: a row never points to nothing
    row = ExerciseSession(
        client_session_id=upload.client_session_id,
        patient_id=patient_id,
        device_id=device_id,
        exercise_id=exercise.id,
        started_at=upload.started_at,
        duration_s=raw.duration,
        n_frames=raw.n_frames,
        file_format=FILE_FORMAT,
        file_key=stored_file.key,
        file_size=len(upload.data),
        content_hash=upload.content_hash,
        processing_version=__version__,
        processing_params=json_ready(upload.payload.params),
        status="processed" if doc is not None else "failed",
        error=error,
        created_at=utcnow(),
    )
    try:
        with db_session.begin_nested():
            db_session.add(row)
    except IntegrityError:
        stored = find_session(db_session=db_session, patient_id=patient_id, client_session_id=upload.client_session_id)
        if stored is None:
            raise
        return _same_or_conflict(stored, upload, db_session), False, None
    if doc is not None:
        stored_doc = doc.model_dump(mode="json")
        db_session.add(
            SessionMetric(session_id=row.id, document=stored_doc, created_at=utcnow(), **scalar_columns(doc))
        )
        db_session.flush()
    return row, True, doc


# ---------------------------------------------------------------------------------------------- reads

_ITEM_COLUMNS = (
    ExerciseSession,
    Exercise.slug,
    SessionMetric.repetitions,
    SessionMetric.rom_deg,
    SessionMetric.quality_ok,
)


def _with_metrics(*columns: Any) -> Select[Any]:
    return (
        select(*columns)
        .select_from(ExerciseSession)
        .outerjoin(Exercise, Exercise.id == ExerciseSession.exercise_id)
        .outerjoin(SessionMetric, SessionMetric.session_id == ExerciseSession.id)
    )


def visible_patients_filter(
    *, role: str, user_id: int | None, device_patient_id: int | None
) -> ColumnElement[bool] | None:
    """Returns the WHERE clause of the sessions a caller may list: own, own patient's, assigned patients' or all."""
    if role == "device":
        return ExerciseSession.patient_id == device_patient_id
    if role == "patient":
        return ExerciseSession.patient_id == user_id
    if role == "therapist":
        assigned = select(TherapistPatient.patient_id).where(TherapistPatient.therapist_id == user_id)
        return ExerciseSession.patient_id.in_(assigned)
    return None  # admin: everyone


def list_sessions(
    *,
    db_session: Session,
    visible: ColumnElement[bool] | None,
    patient_id: int | None,
    exercise_id: int | None,
    since: dt.datetime | None,
    limit: int,
    offset: int,
) -> tuple[list[tuple[Any, ...]], int]:
    """Returns one page of (session, exercise slug, repetitions, rom_deg, quality_ok), newest first, and the total.

    visible: the caller's visible_patients_filter (None = every patient). The file bytes are never loaded.
    """
    query = _with_metrics(*_ITEM_COLUMNS)
    conditions = [c for c in (visible,) if c is not None]
    if patient_id is not None:
        conditions.append(ExerciseSession.patient_id == patient_id)
    if exercise_id is not None:
        conditions.append(ExerciseSession.exercise_id == exercise_id)
    if since is not None:
        conditions.append(ExerciseSession.started_at >= since)
    query = query.where(*conditions)
    total = db_session.scalar(select(func.count()).select_from(ExerciseSession).where(*conditions)) or 0
    rows = db_session.execute(
        query.order_by(ExerciseSession.started_at.desc(), ExerciseSession.id.desc()).limit(limit).offset(offset)
    ).all()
    return [tuple(r) for r in rows], total


def dashboard_patients(*, db_session: Session, caller: Caller, limit: int, offset: int) -> tuple[list[User], int]:
    """Returns one page of the patients the caller (deps.Caller) may see, by id, and their total.

    The total is counted only when the page does not tell it (a full page, or an empty page past the start).
    """
    query = visible_patients_query(caller)
    patients = list(db_session.scalars(query.order_by(User.id).limit(limit).offset(offset)))
    if len(patients) < limit and (patients or offset == 0):
        return patients, offset + len(patients)
    return patients, db_session.scalar(select(func.count()).select_from(query.subquery())) or 0


def get_session_row(*, db_session: Session, session_id: int) -> tuple[Any, ...]:
    """Returns (session, exercise slug, repetitions, rom_deg, quality_ok, document) or raises SessionNotFound."""
    row = db_session.execute(
        _with_metrics(*_ITEM_COLUMNS, SessionMetric.document).where(ExerciseSession.id == session_id)
    ).first()
    if row is None:
        raise missing(session_id)
    return tuple(row)


def missing(session_id: int) -> SessionNotFound:
    """Returns the error for a session that does not exist, or that the caller has no right to know of."""
    return SessionNotFound(f"session {session_id} does not exist")


def session_patient(*, db_session: Session, session_id: int) -> int:
    """Returns the patient id of a session or raises SessionNotFound."""
    patient_id = db_session.scalar(select(ExerciseSession.patient_id).where(ExerciseSession.id == session_id))
    if patient_id is None:
        raise missing(session_id)
    return patient_id


def session_file(*, db_session: Session, session_id: int) -> bytes:
    """Returns the stored .khs bytes of a session, read from the object store and checked against its sha256;
    raises SessionNotFound, SessionFileRemoved (retention), StoredObjectMissing or StoredObjectCorrupt."""
    row = db_session.execute(
        select(
            ExerciseSession.file_key,
            ExerciseSession.content_hash,
            ExerciseSession.file_bytes,
            ExerciseSession.file_removed_at,
        ).where(ExerciseSession.id == session_id)
    ).first()
    if row is None:
        raise missing(session_id)
    if row.file_key:
        return get_store().get(row.file_key, row.content_hash)
    if row.file_bytes is None:
        raise removed(session_id, row.file_removed_at)
    return row.file_bytes


def require_recording(*, db_session: Session, session_id: int) -> None:
    """Raises SessionNotFound when the session does not exist, SessionFileRemoved when the retention period removed
    its recording (neither an object key nor bytes in the row)."""
    row = db_session.execute(
        select(ExerciseSession.file_key, ExerciseSession.file_removed_at, ExerciseSession.file_bytes.is_not(None))
        .where(ExerciseSession.id == session_id)
    ).first()  # fmt: skip
    if row is None:
        raise missing(session_id)
    if not row[0] and not row[2]:
        raise removed(session_id, row[1])


def removed(session_id: int, removed_at: dt.datetime | None) -> SessionFileRemoved:
    """Returns the error for a session whose recording the clinic's retention period removed (on removed_at, UTC;
    None: before the date was kept)."""
    when = f" on {removed_at:%Y-%m-%d}" if removed_at is not None else ""
    return SessionFileRemoved(
        f"This session was removed{when} under the clinic's retention policy: its recording (curves, replay, "
        f"exports) is gone; its metrics are kept (session {session_id})"
    )


def find_exercise_id(*, db_session: Session, slug: str) -> int:
    """Returns the id of the exercise with this slug or raises ExerciseNotFound."""
    exercise_id = db_session.scalar(select(Exercise.id).where(Exercise.slug == slug))
    if exercise_id is None:
        raise ExerciseNotFound(f"exercise '{slug}' does not exist")
    return exercise_id


# ---------------------------------------------------------------------------------------------- what the routers share


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
