"""Camera sets whose page went away for good (a tab closed mid-set and never opened again) are ended by a job-queue
worker, so their landmark batches are not kept forever.

Every COACH_CAMERA_SWEEP_S each worker (backend.jobs.worker.work) queues one `camera_end` job per set still
recording whose last batch (or, with none, its start) is older than COACH_CAMERA_SET_IDLE_HOURS. The job's key
names the set and its last batch number, so several workers queue it once, and a set that got batches again after
a job ran gets a new job when it is idle again. The job locks the set, checks again that it is still recording and
idle, and ends it as the page would (finish.end_set, end reason "abandoned"): stored once when its batches make a
valid session (the session's client id is the set's id: idempotent), else marked failed; its batches are deleted
either way.
"""

from __future__ import annotations

import datetime as dt
import uuid
from typing import Any

from sqlalchemy import func, select
from sqlalchemy.orm import Session

from backend.audit.service import record
from backend.camera import finish, live_count, service
from backend.camera.models import CameraBatch, CameraSet
from backend.database import utcnow
from backend.exceptions import AppError
from backend.jobs import queue

JOB_KIND = "camera_end"
END_REASON = "abandoned"


def _cutoff(idle_hours: float, now: dt.datetime | None) -> dt.datetime:
    return (now or utcnow()) - dt.timedelta(hours=idle_hours)


def idle_sets(*, db_session: Session, idle_hours: float, now: dt.datetime | None = None) -> list[tuple[uuid.UUID, int]]:
    """Returns (set id, last batch number) of every set still recording that received nothing for idle_hours: its
    newest batch (its start when it has none) is older than now - idle_hours."""
    newest = (
        select(CameraBatch.set_id, func.max(CameraBatch.received_at).label("received_at"))
        .group_by(CameraBatch.set_id)
        .subquery()
    )
    last_seen = func.coalesce(newest.c.received_at, CameraSet.started_at)
    query = (
        select(CameraSet.id, CameraSet.last_seq)
        .outerjoin(newest, newest.c.set_id == CameraSet.id)
        .where(CameraSet.status == "recording", last_seen < _cutoff(idle_hours, now))
        .order_by(CameraSet.started_at)
    )
    return [(set_id, last_seq) for set_id, last_seq in db_session.execute(query).all()]


def queue_idle_sets(*, db_session: Session, idle_hours: float, now: dt.datetime | None = None) -> int:
    """Queues a camera_end job for each idle set (idle_sets) not queued yet; returns how many were added. Flushes."""
    found = idle_sets(db_session=db_session, idle_hours=idle_hours, now=now)
    items = ((f"{JOB_KIND}:{set_id}:{last_seq}", {"set_id": str(set_id)}) for set_id, last_seq in found)
    return queue.enqueue(db_session=db_session, kind=JOB_KIND, items=items)


def end_idle_set(
    *,
    db_session: Session,
    set_id: uuid.UUID,
    idle_hours: float,
    max_frames: int,
    max_decoded_bytes: int,
    now: dt.datetime | None = None,
) -> dict[str, Any]:
    """Ends one set idle for idle_hours (locked here) and returns what became of it: {"set_id", "status",
    "session_id", "ended": whether this call ended it}. A set that ended already, or got batches again since it was
    queued, is left as it is. When its batches do not make a valid session the set is marked failed with the reason.
    Flushes; the worker commits with the job."""
    row = db_session.scalar(
        select(CameraSet).where(CameraSet.id == set_id).with_for_update().execution_options(populate_existing=True)
    )
    if row is None:  # the patient was deleted meanwhile (the set goes with them)
        return {"set_id": str(set_id), "status": "gone", "session_id": None, "ended": False}
    newest = db_session.scalar(select(func.max(CameraBatch.received_at)).where(CameraBatch.set_id == row.id))
    last_seen = service.aware(newest or row.started_at)
    if row.status != "recording" or last_seen >= _cutoff(idle_hours, now):
        return {"set_id": str(row.id), "status": row.status, "session_id": row.session_id, "ended": False}
    try:
        with db_session.begin_nested():
            finish.end_set(db_session=db_session, row=row, last_seq=row.last_seq, reason=END_REASON,
                           max_frames=max_frames, max_decoded_bytes=max_decoded_bytes)  # fmt: skip
    except (AppError, ValueError) as exc:  # the batches do not make a session the server accepts
        db_session.refresh(row)
        row.status, row.ended_at, row.end_reason = "failed", utcnow(), END_REASON
        row.error = (
            f"the set was ended after {idle_hours:g} h without news from its page and could not be stored: {exc}"
        )
        service.drop_batches(db_session=db_session, set_id=row.id)
        live_count.forget(row.id)
        db_session.flush()
    record(db_session=db_session, caller=None, action="camera.end", object_type="camera_set", object_id=str(row.id),
           patient_id=row.patient_id, detail={"status": row.status, "session_id": row.session_id,
                                              "reason": END_REASON})  # fmt: skip
    return {"set_id": str(row.id), "status": row.status, "session_id": row.session_id, "ended": True}
