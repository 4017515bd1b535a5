"""Admin API of re-analysis: queue it, follow its progress; and a session's metrics of every analysis version."""

from __future__ import annotations

import datetime as dt
from typing import Annotated, Any, Literal

from fastapi import APIRouter, Query, status
from pydantic import BaseModel, Field
from sqlalchemy import select

from backend.audit.service import record
from backend.deps import AdminCaller, CurrentCaller, DbSession, require_patient_access
from backend.exceptions import AUTH_ERRORS, InvalidInput, NotFound, PatientNotFound, SessionNotFound, error_responses
from backend.jobs.listing import error_words, list_batches, list_jobs
from backend.jobs.models import SessionMetricVersion
from backend.jobs.queue import progress
from backend.records.reanalysis import OLDER, enqueue_reanalysis
from backend.schemas import IdPath
from backend.sessions import service
from backend.sessions.metrics import ANALYSIS_VERSION
from backend.sessions.models import ExerciseSession, SessionMetric
from backend.users.models import User
from kinect_agent.analysis.document import AnalysisDocument, read_document, read_if_readable
from kinect_agent.processing.pipeline import VERSION as PIPELINE_VERSION
from kinect_agent.processing.provenance import settings_id

router = APIRouter(prefix="/api/v1", tags=["re-analysis"])


class BatchNotFound(NotFound):
    pass


class ReanalysisIn(BaseModel):
    """Which stored sessions to analyse again (all when every filter is empty)."""

    model_config = {"json_schema_extra": {"examples": [{"patient_id": 3, "since": "2026-01-01", "exercise": "squat",
                    "pipeline": False}]}}  # fmt: skip
    patient_id: int | None = None
    since: dt.date | None = None
    exercise: str | None = Field(default=None, max_length=64)
    pipeline: bool = Field(
        default=False,
        description="also filter the raw recording again with today's pipeline where the stored file was filtered by "
        "another pipeline version or other settings, or not at all (a new session file; the earlier one is kept); "
        "false: the metrics only, from the stored filtered recording",
    )


class ProgressOut(BaseModel):
    """Progress of one re-analysis batch: jobs per state."""

    model_config = {"json_schema_extra": {"examples": [{"batch": "reanalyze-0a1b2c3d4e5f", "analysis_version":
                    ANALYSIS_VERSION, "queued": 10, "running": 2, "done": 30, "failed": 0, "total": 42}]}}  # fmt: skip
    batch: str
    analysis_version: str
    queued: int
    running: int
    done: int
    failed: int
    total: int


class MetricVersionOut(BaseModel):
    """One metrics document of a session with the analysis version that made it (current=True: today's) and the
    session file it was computed from: its sha256 and the pipeline that filtered it (null: not recorded)."""

    model_config = {"json_schema_extra": {"examples": [{"analysis_version": ANALYSIS_VERSION, "current": True,
                    "repetitions": 10, "rom_deg": 88.0, "balance_sway_m_s": 0.021, "replaced_at": None,
                    "file_sha256": "ab12" + 60 * "0", "pipeline_version": "ukf-4pass v1",
                    "pipeline_settings": "3f2c0a1b9d8e", "refiltered": None, "file_kept": True}]}}  # fmt: skip
    analysis_version: str
    current: bool
    repetitions: int | None
    rom_deg: float | None
    balance_sway_m_s: float | None
    replaced_at: dt.datetime | None
    file_sha256: str | None = Field(description="sha256 of the session file these metrics came from (null: unknown)")
    pipeline_version: str | None = Field(description="the pipeline that filtered that file (params.pipeline)")
    pipeline_settings: str | None = Field(description="a short name of that pipeline's settings (12 hex digits)")
    refiltered: str | None = Field(description="why the server filtered the raw recording again to make that file")
    file_kept: bool = Field(description="whether that file is still stored (false: unknown, or removed)")


class BatchOut(BaseModel):
    """One re-analysis batch on the admin page: jobs per state, who queued it for which patient, when."""

    model_config = {"json_schema_extra": {"examples": [{"batch": "reanalyze-0a1b2c3d4e5f", "queued": 0, "running": 1,
                    "done": 40, "failed": 1, "total": 42, "created_at": "2026-11-27T05:00:00Z", "finished_at": None,
                    "queued_by": "admin@demo.clinic", "patient_id": None}]}}  # fmt: skip
    batch: str
    queued: int
    running: int
    done: int
    failed: int
    total: int
    created_at: dt.datetime
    finished_at: dt.datetime | None = Field(description="when its last job ended; null while any is queued or running")
    queued_by: str | None = Field(description="e-mail of the admin who queued it (null: the CLI)")
    patient_id: int | None = Field(description="the one patient it is about; null: every patient")


class ReanalysisOverviewOut(BaseModel):
    """The server's analysis and pipeline versions (what a new re-analysis uses) and the newest re-analysis batches."""

    model_config = {"json_schema_extra": {"examples": [{"analysis_version": ANALYSIS_VERSION,
                    "pipeline_version": PIPELINE_VERSION, "batches": [
                    BatchOut.model_config["json_schema_extra"]["examples"][0]]}]}}  # type: ignore[index]  # fmt: skip

    analysis_version: str
    pipeline_version: str = Field(PIPELINE_VERSION, description="the pipeline a re-analysis with pipeline=true uses")
    batches: list[BatchOut]


class JobOut(BaseModel):
    """One job of the queue; `error` says in words why it failed or was retried (no traceback)."""

    model_config = {"json_schema_extra": {"examples": [{"id": 7, "kind": "reanalyze", "batch": "reanalyze-0a1b2c3d4e5f",
                    "status": "failed", "attempts": 3, "max_attempts": 3, "session_id": 31,
                    "error": "The session's file is missing from the object store (run `coach-server storage check`)"
                    ": no object session/ab/ab12...", "changed": None, "created_at": "2026-11-27T05:00:00Z",
                    "finished_at": "2026-11-27T05:03:00Z"}]}}  # fmt: skip
    id: int
    kind: str
    batch: str | None
    status: str = Field(description="queued, running, done or failed (after max_attempts tries)")
    attempts: int
    max_attempts: int
    session_id: int | None
    error: str | None
    changed: bool | None = Field(description="done: whether the metrics changed; null otherwise")
    created_at: dt.datetime
    finished_at: dt.datetime | None


@router.get("/reanalysis", response_model=ReanalysisOverviewOut, responses=error_responses(*AUTH_ERRORS))
def reanalysis_overview(
    caller: AdminCaller, db_session: DbSession, limit: Annotated[int, Query(ge=1, le=100)] = 20
) -> ReanalysisOverviewOut:
    """Returns today's analysis version and the newest re-analysis batches with their progress (admins)."""
    rows = list_batches(db_session=db_session, kind="reanalyze", limit=limit)
    ids = {r.queued_by for r in rows if r.queued_by is not None}
    emails = dict(db_session.execute(select(User.id, User.email).where(User.id.in_(ids))).all()) if ids else {}
    batches = [BatchOut(batch=r.batch, queued=r.queued, running=r.running, done=r.done, failed=r.failed,
                        total=r.total, created_at=r.created_at, finished_at=r.finished_at,
                        queued_by=emails.get(r.queued_by) if r.queued_by is not None else None,
                        patient_id=r.patient_id) for r in rows]  # fmt: skip
    return ReanalysisOverviewOut(analysis_version=ANALYSIS_VERSION, batches=batches)


@router.get("/jobs", response_model=list[JobOut], responses=error_responses(*AUTH_ERRORS))
def read_jobs(
    caller: AdminCaller,
    db_session: DbSession,
    batch: Annotated[str | None, Query(max_length=64)] = None,
    state: Annotated[Literal["queued", "running", "done", "failed"] | None, Query(alias="status")] = None,
    limit: Annotated[int, Query(ge=1, le=500)] = 50,
) -> list[JobOut]:
    """Returns the newest jobs of the queue, of one batch or in one state when asked (admins)."""
    jobs = list_jobs(db_session=db_session, batch=batch, status=state, limit=limit)
    return [JobOut(id=j.id, kind=j.kind, batch=j.batch, status=j.status, attempts=j.attempts,
                   max_attempts=j.max_attempts, session_id=(j.payload or {}).get("session_id"),
                   error=error_words(j.error), changed=(j.result or {}).get("changed") if j.status == "done" else None,
                   created_at=j.created_at, finished_at=j.finished_at) for j in jobs]  # fmt: skip


@router.post("/reanalysis", response_model=ProgressOut, status_code=status.HTTP_202_ACCEPTED,
             responses=error_responses(*AUTH_ERRORS, PatientNotFound, InvalidInput))  # fmt: skip
def queue_reanalysis(body: ReanalysisIn, caller: AdminCaller, db_session: DbSession) -> ProgressOut:
    """Queues the re-analysis of the matching stored sessions (admins); workers (`coach-server worker`) run it."""
    batch, _ = enqueue_reanalysis(db_session=db_session, patient_id=body.patient_id, since=body.since,
                                  exercise=body.exercise, pipeline=body.pipeline)  # fmt: skip
    record(db_session=db_session, caller=caller, action="reanalysis.queue", object_type="batch", object_id=batch,
           patient_id=body.patient_id, detail=body.model_dump(mode="json"))  # fmt: skip
    return ProgressOut(batch=batch, analysis_version=ANALYSIS_VERSION, **progress(db_session=db_session, batch=batch))


@router.get("/reanalysis/{batch}", response_model=ProgressOut, responses=error_responses(*AUTH_ERRORS, BatchNotFound))
def reanalysis_progress(batch: str, caller: AdminCaller, db_session: DbSession) -> ProgressOut:
    """Returns the progress of a re-analysis batch (admins)."""
    counts = progress(db_session=db_session, batch=batch)
    if counts["total"] == 0:
        raise BatchNotFound(f"re-analysis batch {batch!r} does not exist or had nothing to do")
    return ProgressOut(batch=batch, analysis_version=ANALYSIS_VERSION, **counts)


def _sway(doc: AnalysisDocument | None) -> float | None:
    return doc.balance.sway_velocity_m_s if doc is not None and doc.balance is not None else None


@router.get("/sessions/{session_id}/metric-versions", response_model=list[MetricVersionOut],
            responses=error_responses(*AUTH_ERRORS, SessionNotFound))  # fmt: skip
def metric_versions(session_id: IdPath, caller: CurrentCaller, db_session: DbSession) -> list[MetricVersionOut]:
    """Returns a session's metrics under each analysis version, today's first, each with the session file it came
    from and the pipeline that filtered that file: what a re-analysis changed."""
    patient_id = service.session_patient(db_session=db_session, session_id=session_id)
    require_patient_access(patient_id, caller=caller, db_session=db_session, allow_device=False,
                           hidden_as=service.missing(session_id))  # fmt: skip
    current = db_session.scalar(select(SessionMetric).where(SessionMetric.session_id == session_id))
    session = db_session.get(ExerciseSession, session_id)
    out = []
    if current is not None and session is not None:
        doc = read_document(current.document)
        files = _file_fields(session.content_hash, session.processing_params, kept=session.file_removed_at is None)
        out.append(MetricVersionOut(analysis_version=doc.analysis_version or OLDER, current=True,
                                    repetitions=current.repetitions, rom_deg=current.rom_deg,
                                    balance_sway_m_s=_sway(doc), replaced_at=None, **files))  # fmt: skip
    newest_first = (SessionMetricVersion.replaced_at.desc(), SessionMetricVersion.id.desc())
    older = db_session.scalars(select(SessionMetricVersion).where(SessionMetricVersion.session_id == session_id)
                               .order_by(*newest_first))  # fmt: skip
    for v in older:
        old = read_if_readable(v.document)  # a replaced document may be of any shape the server ever stored
        files = _file_fields(v.file_hash, v.processing_params, kept=v.file_key is not None)
        out.append(MetricVersionOut(analysis_version=v.analysis_version, current=False,
                                    repetitions=old.repetitions if old else None, rom_deg=old.rom_deg if old else None,
                                    balance_sway_m_s=_sway(old), replaced_at=v.replaced_at, **files))  # fmt: skip
    return out


def _file_fields(sha256: str | None, params: dict[str, Any] | None, *, kept: bool) -> dict[str, Any]:
    """Returns the file fields of MetricVersionOut from a file's sha256 and params (None: not recorded)."""
    params = params if isinstance(params, dict) else {}
    made_by, again = params.get("pipeline"), params.get("refiltered")
    return {"file_sha256": sha256, "pipeline_version": made_by if isinstance(made_by, str) else None,
            "pipeline_settings": settings_id(params.get("config")), "file_kept": kept and sha256 is not None,
            "refiltered": again.get("reason") if isinstance(again, dict) else None}  # fmt: skip
