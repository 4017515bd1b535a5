"""Re-analysis of stored sessions with today's analysis: enqueue (CLI, admin API) and the job a worker runs.

The job of a session: read its file from the object store (checked), decode it, compute the metrics document with
today's analysis (backend.sessions.metrics.ANALYSIS_VERSION), move the current document to
session_metric_version with its version, and store the new one. A session whose document is already of today's
version is left as it is, so a job run twice (a worker died after the work, before marking it done) changes
nothing the second time. Suggestions are not made again (the patient saw them already).
"""

from __future__ import annotations

import datetime as dt
import uuid
from typing import Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from backend.database import utcnow
from backend.exceptions import InvalidInput, PatientNotFound
from backend.exercises.library import EXERCISES
from backend.exercises.models import Exercise
from backend.jobs.models import SessionMetricVersion
from backend.jobs.queue import enqueue
from backend.sessions.metrics import ANALYSIS_VERSION, metrics_document, scalar_columns
from backend.sessions.models import ExerciseSession, SessionMetric
from backend.sessions.service import session_file
from backend.suggestions.context import plan_targets, session_history
from backend.users.models import User
from kinect_agent.analysis.document import read_if_readable
from kinect_agent.formats import session_file as khs

KIND = "reanalyze"
OLDER = "before 2026.11.27"  # the version of documents made before analysis versions were recorded


def enqueue_reanalysis(
    *,
    db_session: Session,
    patient_id: int | None = None,
    since: dt.date | None = None,
    exercise: str | None = None,
) -> tuple[str, int]:
    """Queues one job per stored session matching the filters whose document is not of today's version (a job of
    this version that failed is queued again with fresh tries); returns (batch id, jobs added). Flushes.

    Raises PatientNotFound when patient_id names no patient, InvalidInput when exercise is not in the library (a
    typo would otherwise queue nothing and say "0 session(s)", as if the sessions were up to date).
    """
    if (
        patient_id is not None
        and db_session.scalar(select(User.id).where(User.id == patient_id, User.role == "patient")) is None
    ):
        raise PatientNotFound(f"no patient with id {patient_id}")
    if exercise is not None and db_session.scalar(select(Exercise.id).where(Exercise.slug == exercise)) is None:
        known = ", ".join(db_session.scalars(select(Exercise.slug).order_by(Exercise.slug)))
        raise InvalidInput(f"no exercise {exercise!r} in the library (known: {known})")
    query = select(ExerciseSession.id).where(
        (ExerciseSession.file_key.is_not(None)) | (ExerciseSession.file_bytes.is_not(None))
    )
    if patient_id is not None:
        query = query.where(ExerciseSession.patient_id == patient_id)
    if since is not None:
        query = query.where(ExerciseSession.started_at >= dt.datetime.combine(since, dt.time(), tzinfo=dt.UTC))
    if exercise is not None:
        query = query.join(Exercise, Exercise.id == ExerciseSession.exercise_id).where(Exercise.slug == exercise)
    batch = f"reanalyze-{uuid.uuid4().hex[:12]}"
    ids = db_session.scalars(query.order_by(ExerciseSession.id)).all()
    items = ((f"{KIND}:{sid}:{ANALYSIS_VERSION}", {"session_id": sid}) for sid in ids)
    return batch, enqueue(db_session=db_session, kind=KIND, items=items, batch=batch, retry_failed=True)


def _version(stored: dict[str, Any] | None) -> str:
    """Returns the analysis version of a stored document (OLDER without one, or when no schema reads it)."""
    doc = read_if_readable(stored)
    return (doc.analysis_version if doc is not None else None) or OLDER


def reanalyze_session(
    *, db_session: Session, session_id: int, max_frames: int, max_decoded_bytes: int
) -> dict[str, Any]:
    """Runs the job of one session (module doc); returns {"session_id", "changed", "from", "to"}. Flushes."""
    session = db_session.get(ExerciseSession, session_id)
    if session is None:
        return {"session_id": session_id, "changed": False, "skipped": "the session no longer exists"}
    metric = db_session.scalar(select(SessionMetric).where(SessionMetric.session_id == session_id))
    old_version = _version(metric.document) if metric else None
    if old_version == ANALYSIS_VERSION:
        return {"session_id": session_id, "changed": False, "from": old_version, "to": ANALYSIS_VERSION}
    slug = db_session.scalar(select(Exercise.slug).where(Exercise.id == session.exercise_id))
    spec = EXERCISES.get(slug) if slug else None
    if spec is None:
        return {"session_id": session_id, "changed": False, "skipped": f"exercise {slug!r} is not in the library"}
    payload = khs.decode(session_file(db_session=db_session, session_id=session_id), max_frames=max_frames,
                         max_decoded_bytes=max_decoded_bytes)  # fmt: skip
    target_reps, _ = plan_targets(db_session=db_session, patient_id=session.patient_id,
                                  exercise_id=session.exercise_id, on=session.started_at.date())  # fmt: skip
    history = [doc for _, doc in session_history(db_session=db_session, session=session) if doc is not None]
    doc = metrics_document(payload, spec, target_reps=target_reps, history=history)
    stored = doc.model_dump(mode="json")
    if metric is None:
        db_session.add(
            SessionMetric(session_id=session_id, document=stored, created_at=utcnow(), **scalar_columns(doc))
        )
    else:
        db_session.add(SessionMetricVersion(session_id=session_id, analysis_version=old_version,
                                            document=metric.document, replaced_at=utcnow()))  # fmt: skip
        metric.document = stored
        for name, value in scalar_columns(doc).items():
            setattr(metric, name, value)
    session.status, session.error = "processed", None
    db_session.flush()
    return {"session_id": session_id, "changed": True, "from": old_version, "to": ANALYSIS_VERSION}
