"""The replay build on the job queue: a page asks for a session's replay, a worker builds it off the request path.

`request_replay` is what a request does: the recording is ready (stored, of today's scene version), or one job is
queued to build it (key `replay:<session id>:<scene version>`, so concurrent requests and several server
processes queue it once, and several workers build it once), or its build failed (said in words). `run` is the
job: it builds and stores the recording unless it is stored already (a job run twice builds once).
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass
from typing import Any

from sqlalchemy import select, update
from sqlalchemy.orm import Session

from backend.database import utcnow
from backend.jobs.listing import error_words
from backend.jobs.models import Job
from backend.jobs.queue import enqueue
from backend.replay import scene, service
from backend.sessions.models import ExerciseSession
from backend.sessions.service import missing, removed

KIND = "replay"


@dataclass(frozen=True)
class ReplayState:
    """Where a session's replay is: "ready", "preparing" (queued or being built) or "failed"; detail in words."""

    state: str
    detail: str


def job_key(session_id: int) -> str:
    """Returns the queue key of the build of one session's replay at today's scene version."""
    return f"{KIND}:{session_id}:{scene.VERSION}"


def _waiting(job: Job, now: dt.datetime) -> str:
    if job.status == "running":
        return "A worker is building the replay."
    if job.error:
        return f"The last try failed; a worker will try again. {error_words(job.error)}"
    waited = max(0, int((now - job.created_at).total_seconds()))
    if waited < 10:
        return "The replay is queued; a worker will build it in a moment."
    return f"The replay has waited {waited} s for a worker; is `coach-server worker` running?"


def request_replay(*, db_session: Session, session_id: int) -> ReplayState:
    """Returns the state of a session's replay, queueing its build when it is neither stored nor queued; flushes.

    Raises SessionNotFound, or SessionFileRemoved when the retention period removed the recording.
    """
    if service.stored_replay_key(db_session=db_session, session_id=session_id) is not None:
        return ReplayState("ready", "The replay is ready.")
    row = db_session.execute(
        select(ExerciseSession.file_key, ExerciseSession.file_removed_at, ExerciseSession.file_bytes.is_not(None))
        .where(ExerciseSession.id == session_id)
    ).first()  # fmt: skip
    if row is None:
        raise missing(session_id)
    if not row[0] and not row[2]:
        raise removed(session_id, row[1])
    key = job_key(session_id)
    job = db_session.scalar(select(Job).where(Job.key == key))
    if job is None:
        enqueue(db_session=db_session, kind=KIND, items=[(key, {"session_id": session_id})])
        job = db_session.scalar(select(Job).where(Job.key == key))
    elif job.status == "done":  # built once, and the recording went since (a newer build replaced it): again
        again = {"status": "queued", "attempts": 0, "run_after": utcnow(), "error": None, "finished_at": None}
        db_session.execute(update(Job).where(Job.id == job.id, Job.status == "done").values(**again))
        db_session.refresh(job)
    if job is not None and job.status == "failed":
        return ReplayState("failed", error_words(job.error) or "The replay could not be built.")
    return ReplayState("preparing", _waiting(job, utcnow()) if job is not None else "The replay is queued.")


def run(*, db_session: Session, session_id: int, max_frames: int, max_decoded_bytes: int) -> dict[str, Any]:
    """Runs the job of one session: builds and stores its replay unless stored already; returns what it did."""
    if db_session.get(ExerciseSession, session_id) is None:
        return {"session_id": session_id, "built": False, "skipped": "the session no longer exists"}
    if service.stored_replay_key(db_session=db_session, session_id=session_id) is not None:
        return {"session_id": session_id, "built": False, "version": scene.VERSION}
    replay = service.build_and_store(db_session=db_session, session_id=session_id, max_frames=max_frames,
                                     max_decoded_bytes=max_decoded_bytes)  # fmt: skip
    return {"session_id": session_id, "built": True, "version": scene.VERSION, "n_frames": replay.n_frames,
            "size": len(replay.data)}  # fmt: skip
