"""Admin API of re-analysis: queue it, follow its progress; and a session's metrics of every analysis version."""

from __future__ import annotations

import datetime as dt

from fastapi import APIRouter, status
from pydantic import BaseModel, Field
from sqlalchemy import select

from backend.audit.service import record
from backend.deps import AdminCaller, CurrentCaller, DbSession, require_patient_access
from backend.exceptions import AUTH_ERRORS, NotFound, SessionNotFound, error_responses
from backend.jobs.models import SessionMetricVersion
from backend.jobs.queue import progress
from backend.records.reanalysis import enqueue_reanalysis
from backend.schemas import IdPath
from backend.sessions import service
from backend.sessions.metrics import ANALYSIS_VERSION
from backend.sessions.models import SessionMetric

router = APIRouter(prefix="/api/v1", tags=["re-analysis"])


class BatchNotFound(NotFound):
    pass


class ReanalysisIn(BaseModel):
    """Which stored sessions to analyse again (all when every filter is empty)."""

    model_config = {"json_schema_extra": {"examples": [{"patient_id": 3, "since": "2026-01-01", "exercise": "squat"}]}}
    patient_id: int | None = None
    since: dt.date | None = None
    exercise: str | None = Field(default=None, max_length=64)


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
    """One metrics document of a session with the analysis version that made it (current=True: today's)."""

    model_config = {"json_schema_extra": {"examples": [{"analysis_version": ANALYSIS_VERSION, "current": True,
                    "repetitions": 10, "rom_deg": 88.0, "balance_sway_m_s": 0.021, "replaced_at": None}]}}  # fmt: skip
    analysis_version: str
    current: bool
    repetitions: int | None
    rom_deg: float | None
    balance_sway_m_s: float | None
    replaced_at: dt.datetime | None


@router.post("/reanalysis", response_model=ProgressOut, status_code=status.HTTP_202_ACCEPTED,
             responses=error_responses(*AUTH_ERRORS))  # fmt: skip
def queue_reanalysis(body: ReanalysisIn, caller: AdminCaller, db_session: DbSession) -> ProgressOut:
    """Queues the re-analysis of the matching stored sessions (admins); workers (`coach-server worker`) run it."""
    batch, _ = enqueue_reanalysis(db_session=db_session, patient_id=body.patient_id, since=body.since,
                                  exercise=body.exercise)  # fmt: skip
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


def _sway(doc: dict) -> float | None:
    return ((doc or {}).get("balance") or {}).get("sway_velocity_m_s")


@router.get("/sessions/{session_id}/metric-versions", response_model=list[MetricVersionOut],
            responses=error_responses(*AUTH_ERRORS, SessionNotFound))  # fmt: skip
def metric_versions(session_id: IdPath, caller: CurrentCaller, db_session: DbSession) -> list[MetricVersionOut]:
    """Returns a session's metrics under each analysis version, today's first: what a re-analysis changed."""
    patient_id = service.session_patient(db_session=db_session, session_id=session_id)
    require_patient_access(patient_id, caller=caller, db_session=db_session, allow_device=False,
                           hidden_as=service.missing(session_id))  # fmt: skip
    current = db_session.scalar(select(SessionMetric).where(SessionMetric.session_id == session_id))
    out = []
    if current is not None:
        doc = current.document or {}
        out.append(MetricVersionOut(analysis_version=doc.get("analysis_version", "before 2026.11.27"), current=True,
                                    repetitions=current.repetitions, rom_deg=current.rom_deg,
                                    balance_sway_m_s=_sway(doc), replaced_at=None))  # fmt: skip
    older = db_session.scalars(select(SessionMetricVersion).where(SessionMetricVersion.session_id == session_id)
                               .order_by(SessionMetricVersion.replaced_at.desc()))  # fmt: skip
    for v in older:
        doc = v.document or {}
        out.append(MetricVersionOut(analysis_version=v.analysis_version, current=False,
                                    repetitions=doc.get("repetitions"), rom_deg=doc.get("rom_deg"),
                                    balance_sway_m_s=_sway(doc), replaced_at=v.replaced_at))  # fmt: skip
    return out
