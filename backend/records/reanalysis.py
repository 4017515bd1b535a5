"""Re-analysis of stored sessions with today's analysis (and, asked, today's pipeline): enqueue (CLI, admin API)
and the job a worker runs.

The job of a session: read its file from the object store (checked) and decode it. With pipeline=True, when the
file's filtered recording was not made by today's pipeline for its device (kinect_agent.processing.provenance
.stale_reason: another pipeline.VERSION, other settings, or none), filter its raw recording again with
config_for_device and write a new session file (raw the same, new filtered recording, angle SDs and params, which
name the earlier file's sha256 under "refiltered") to the object store; the session then points at it. Compute the
metrics document with today's analysis (backend.sessions.metrics.ANALYSIS_VERSION), move the current document to
session_metric_version with its version and the file it came from (key, sha256, params: the earlier file stays in
the store), and store the new one. A session already of today's analysis version (and, with pipeline=True, filtered
by today's pipeline) is left as it is, so a job run twice (a worker died after the work, before marking it done)
changes nothing the second time. The worker's commit decides: a crash after the new file was stored and before the
commit leaves an object no row names (harmless; `coach-server storage check --orphans` lists it). Suggestions are
not made again (the patient saw them already).
"""

from __future__ import annotations

import dataclasses
import datetime as dt
import uuid
from dataclasses import dataclass
from typing import Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from backend import __version__
from backend.database import utcnow
from backend.exceptions import InvalidInput, PatientNotFound
from backend.exercises.models import Exercise
from backend.jobs.errors import PermanentJobError
from backend.jobs.models import SessionMetricVersion
from backend.jobs.queue import enqueue
from backend.records.erasure import delete_after_commit, unnamed_keys
from backend.replay.models import SessionReplay
from backend.sessions.history import plan_targets, session_history
from backend.sessions.metrics import ANALYSIS_VERSION, json_ready, metrics_document, scalar_columns
from backend.sessions.models import ExerciseSession, SessionMetric
from backend.sessions.service import session_file
from backend.storage import get_store
from backend.users.models import User
from kinect_agent.analysis.document import AnalysisDocument, read_if_readable
from kinect_agent.analysis.exercise import EXERCISES, ExerciseSpec
from kinect_agent.formats import session_file as khs
from kinect_agent.processing import provenance
from kinect_agent.processing.config import config_for_device
from kinect_agent.processing.pipeline import process

KIND = "reanalyze"
OLDER = "before 2026.11.27"  # the version of documents made before analysis versions were recorded
NO_METRICS = "none"  # the version of a session_metric_version row kept for a session without metrics


class RecordingNotFilterable(PermanentJobError):
    """Today's pipeline refuses the stored raw recording (e.g. no joint tracked in any frame): the job fails at once
    and the session keeps its file and metrics."""


def job_key(session_id: int, *, pipeline: bool) -> str:
    """Returns the queue key of a session's re-analysis: once per analysis version, and with pipeline=True once per
    today's pipeline too (provenance.todays_id), so a new version or setting queues it again."""
    key = f"{KIND}:{session_id}:{ANALYSIS_VERSION}"
    return f"{key}:pipeline-{provenance.todays_id()}" if pipeline else key


def enqueue_reanalysis(
    *,
    db_session: Session,
    patient_id: int | None = None,
    since: dt.date | None = None,
    exercise: str | None = None,
    pipeline: bool = False,
) -> tuple[str, int]:
    """Queues one job per stored session matching the filters that has no job of today's version yet (job_key; a job
    that failed is queued again with fresh tries); returns (batch id, jobs added). pipeline: the jobs also filter
    the raw recording again where the stored file was not filtered by today's pipeline (module doc). Flushes.

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
    items = ((job_key(sid, pipeline=pipeline), {"session_id": sid, "pipeline": pipeline}) for sid in ids)
    return batch, enqueue(db_session=db_session, kind=KIND, items=items, batch=batch, retry_failed=True)


def _version(stored: dict[str, Any] | None) -> str:
    """Returns the analysis version of a stored document (OLDER without one, or when no schema reads it)."""
    doc = read_if_readable(stored)
    return (doc.analysis_version if doc is not None else None) or OLDER


@dataclass(frozen=True)
class FileRef:
    """A session file as the database names it: object key (None: still a database blob), sha256, params."""

    key: str | None
    sha256: str
    params: dict[str, Any]


def refiltered(payload: khs.SessionPayload, *, reason: str, earlier_sha256: str) -> khs.SessionPayload:
    """Returns the payload filtered again by today's pipeline for its device: the same raw recording, session id,
    creation time and recorded_by; a new filtered recording (T, J, 3) m and angle SDs {angle: (T,) degrees}; params
    updated by provenance.pipeline_params plus "refiltered": {"from_sha256", "reason"}. Raises
    RecordingNotFilterable when the pipeline refuses the raw recording."""
    config = config_for_device(payload.raw.meta.device)
    try:
        result = process(payload.raw, config=config)
    except ValueError as exc:
        raise RecordingNotFilterable(f"the pipeline cannot filter the raw recording: {exc}") from None
    params = {**payload.params, **provenance.pipeline_params(config, result),
              "refiltered": {"from_sha256": earlier_sha256, "reason": reason}}  # fmt: skip
    return dataclasses.replace(payload, filtered=result.filtered, angle_sd=result.angle_sd, params=params)


def _metrics(
    db_session: Session, session: ExerciseSession, payload: khs.SessionPayload, spec: ExerciseSpec
) -> AnalysisDocument:
    """Returns today's metrics document (AnalysisDocument) of the payload with the session's plan and history."""
    target_reps, _ = plan_targets(db_session=db_session, patient_id=session.patient_id,
                                  exercise_id=session.exercise_id, on=session.started_at.date())  # fmt: skip
    history = [doc for _, doc in session_history(db_session=db_session, session=session) if doc is not None]
    return metrics_document(payload, spec, target_reps=target_reps, history=history)


def _keep_earlier(db_session: Session, session_id: int, metric: SessionMetric | None, file: FileRef) -> None:
    """Adds the session_metric_version row of the current document (or of none: NO_METRICS) and its file."""
    version = _version(metric.document) if metric is not None else NO_METRICS
    document = metric.document if metric is not None else {"error": "the session had no metrics"}
    db_session.add(SessionMetricVersion(session_id=session_id, analysis_version=version, document=document,
                                        replaced_at=utcnow(), file_key=file.key, file_hash=file.sha256,
                                        processing_params=file.params))  # fmt: skip


def _store_metrics(db_session: Session, session_id: int, metric: SessionMetric | None, doc: AnalysisDocument) -> None:
    """Stores the document as the session's current metrics (a new row, or over the current one)."""
    stored = doc.model_dump(mode="json")
    if metric is None:
        db_session.add(SessionMetric(session_id=session_id, document=stored, created_at=utcnow(),
                                     **scalar_columns(doc)))  # fmt: skip
        return
    metric.document = stored
    for name, value in scalar_columns(doc).items():
        setattr(metric, name, value)


def _point_at(db_session: Session, session: ExerciseSession, data: bytes, params: dict[str, Any]) -> None:
    """Stores the new session file and points the session at it; drops its replays (built from the earlier file;
    rebuilt when next asked), their objects deleted after the commit unless another row names them."""
    stored = get_store().put("session", data)
    session.file_key, session.content_hash, session.file_size = stored.key, stored.sha256, stored.size
    session.file_bytes = None
    session.processing_params, session.processing_version = json_ready(params), __version__
    replays = db_session.scalars(select(SessionReplay).where(SessionReplay.session_id == session.id)).all()
    keys = {r.data_key for r in replays if r.data_key}
    for replay in replays:
        db_session.delete(replay)
    db_session.flush()
    delete_after_commit(db_session, unnamed_keys(db_session, keys))


def _earlier_file(session: ExerciseSession, data: bytes) -> FileRef:
    """Returns the session's current file; one still held as a database blob is put in the object store first, so
    the version row can name it once the session points at its new file."""
    key = session.file_key or get_store().put("session", data).key
    return FileRef(key=key, sha256=session.content_hash, params=dict(session.processing_params or {}))


def reanalyze_session(
    *, db_session: Session, session_id: int, max_frames: int, max_decoded_bytes: int, pipeline: bool = False
) -> dict[str, Any]:
    """Runs the job of one session (module doc); returns {"session_id", "changed", "from", "to", "refiltered":
    the reason in words or None} (or {"session_id", "changed": False, "skipped"}). Flushes.

    Raises RecordingNotFilterable (pipeline=True), the storage errors and SessionFileError of an unreadable file,
    AnalysisError; the session is then unchanged (the worker rolls back)."""
    session = db_session.get(ExerciseSession, session_id)
    if session is None:
        return {"session_id": session_id, "changed": False, "skipped": "the session no longer exists"}
    metric = db_session.scalar(select(SessionMetric).where(SessionMetric.session_id == session_id))
    old_version = _version(metric.document) if metric else None
    unchanged = {"session_id": session_id, "changed": False, "from": old_version, "to": ANALYSIS_VERSION,
                 "refiltered": None}  # fmt: skip
    if old_version == ANALYSIS_VERSION and not pipeline:
        return unchanged
    slug = db_session.scalar(select(Exercise.slug).where(Exercise.id == session.exercise_id))
    spec = EXERCISES.get(slug) if slug else None
    if spec is None:
        return {"session_id": session_id, "changed": False, "skipped": f"exercise {slug!r} is not in the library"}
    data = session_file(db_session=db_session, session_id=session_id)
    payload = khs.decode(data, max_frames=max_frames, max_decoded_bytes=max_decoded_bytes)
    reason = provenance.stale_reason(payload.params, has_filtered=payload.filtered is not None,
                                     device=payload.raw.meta.device) if pipeline else None  # fmt: skip
    if reason is None and old_version == ANALYSIS_VERSION:
        return unchanged
    if reason is not None:
        payload = refiltered(payload, reason=reason, earlier_sha256=session.content_hash)
    doc = _metrics(db_session, session, payload, spec)
    earlier = _earlier_file(session, data) if reason is not None else FileRef(
        key=session.file_key, sha256=session.content_hash, params=dict(session.processing_params or {}))  # fmt: skip
    if metric is not None or reason is not None:
        _keep_earlier(db_session, session_id, metric, earlier)
    _store_metrics(db_session, session_id, metric, doc)
    if reason is not None:
        _point_at(db_session, session, khs.encode(payload), payload.params)
    session.status, session.error = "processed", None
    db_session.flush()
    return {**unchanged, "changed": True, "refiltered": reason}
