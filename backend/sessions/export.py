"""A stored session exported for other software (kinect_agent.export.files): csv, trc, bvh or fhir."""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass
from typing import Any

from sqlalchemy.orm import Session

from backend.exceptions import ExportUnavailable
from backend.feeling.service import get_feeling
from backend.i18n import ENGLISH
from backend.session_texts import reasons
from backend.sessions import service
from backend.sessions.detail import analysis_document, decode_stored
from kinect_agent.analysis.exercise import EXERCISES
from kinect_agent.export.fhir import Feeling, SessionContext
from kinect_agent.export.files import ExportError, ExportFile, export


def _feeling(db_session: Session, session_id: int) -> Feeling | None:
    """Returns what the patient answered after the set (None: not asked or not answered yet)."""
    answer = get_feeling(db_session=db_session, session_id=session_id)
    if answer.answered_at is None:
        return None
    when = answer.answered_at
    when = when.astimezone(dt.UTC).replace(tzinfo=None) if when.tzinfo is not None else when  # stored as UTC
    return Feeling(answer.pain, answer.effort, when.isoformat(timespec="seconds") + "Z")


def export_context(*, db_session: Session, row: tuple[Any, ...]) -> SessionContext:
    """Returns who and what the export of `row` (service.get_session_row) describes, with how the set felt to the
    patient (csv: feeling.csv; fhir: pain and effort Observations); a few small queries, no file read."""
    session = row[0]
    when = session.started_at
    when = when.astimezone(dt.UTC).replace(tzinfo=None) if when.tzinfo is not None else when  # stored as UTC
    return SessionContext(
        session_id=str(session.client_session_id),
        start=when.isoformat(timespec="seconds") + "Z",
        patient_id=session.patient_id,
        device_id=session.device_id,
        feeling=_feeling(db_session, session.id),
    )


@dataclass(frozen=True)
class SessionExports:
    """A session's exports in several formats made from one read of its file: `files` by format, and for each
    format that could not be made, why (`unavailable`, e.g. fhir without metrics)."""

    files: dict[str, ExportFile]
    unavailable: dict[str, str]


def session_exports(
    *,
    db_session: Session,
    row: tuple[Any, ...],
    formats: tuple[str, ...],
    max_frames: int,
    max_decoded_bytes: int,
    context: SessionContext | None = None,
    data: bytes | None = None,
) -> SessionExports:
    """Returns the session of `row` (service.get_session_row) in each of `formats`, its file read (sha256 checked)
    and decoded once, with its metrics document: the stored one, else the file analysed again as the session page
    does (detail.analysis_document, without indicators), and `context` (export_context, read now when None). data:
    the session file when the caller read it already (service.session_file), else it is read here.

    Raises StorageError when the stored file is missing or corrupt, SessionFileRemoved when the retention period
    removed it, InvalidSessionFile when it cannot be decoded; a format the session cannot give is in `unavailable`.
    """
    session, slug, _reps, _rom, _quality, stored = row
    context = context or export_context(db_session=db_session, row=row)
    if data is None:
        data = service.session_file(db_session=db_session, session_id=session.id)
    payload = decode_stored(data, session_id=session.id, max_frames=max_frames, max_decoded_bytes=max_decoded_bytes)
    document, _ = analysis_document(payload, EXERCISES.get(slug) if slug else None, stored)
    if document is not None:  # the FHIR notes say how each indicator was scored, in English
        document = reasons.with_texts(document, ENGLISH)
    files: dict[str, ExportFile] = {}
    unavailable: dict[str, str] = {}
    for fmt in formats:
        try:
            files[fmt] = export(fmt, payload, document=document, context=context, stem=f"session-{session.id}")
        except ExportError as exc:
            unavailable[fmt] = f"session {session.id}: {exc}"
    return SessionExports(files, unavailable)


def session_export(
    *,
    db_session: Session,
    row: tuple[Any, ...],
    fmt: str,
    max_frames: int,
    max_decoded_bytes: int,
    context: SessionContext | None = None,
) -> ExportFile:
    """Returns the session of `row` (service.get_session_row) as `fmt` (session_exports of one format).

    Raises InvalidSessionFile when the stored file cannot be decoded, ExportUnavailable when the format needs metrics
    and none can be had (no known exercise, or the analysis fails).
    """
    built = session_exports(db_session=db_session, row=row, formats=(fmt,), max_frames=max_frames,
                            max_decoded_bytes=max_decoded_bytes, context=context)  # fmt: skip
    if fmt in built.unavailable:
        raise ExportUnavailable(built.unavailable[fmt])
    return built.files[fmt]
