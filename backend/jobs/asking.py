"""What a request does for a result a worker prepares (a replay, a session's detail) that is not stored yet.

`ask` queues the job once (its key decides: concurrent requests and several server processes queue it once),
says where it is in words, and after a failure queues it again when someone asks, up to ASK_ATTEMPTS tries in all:
a build that failed on a passing fault (a worker killed, the store unreachable) is not failed for good, and a file
that can never be built is not tried without end.
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

ASK_ATTEMPTS = 6  # tries of one job in all, the queue's own retries and one more per ask after it failed


@dataclass(frozen=True)
class Asked:
    """Where the job of a result is: "preparing" (queued or running) or "failed" (for good); detail in words."""

    state: str
    detail: str
    job: Job | None


def waiting_words(job: Job, noun: str, now: dt.datetime) -> str:
    """Returns where a queued or running job is, in words; noun: what it prepares ("the replay")."""
    if job.status == "running":
        return f"A worker is building {noun}."
    if job.error:
        return f"The last try failed; a worker will try again. {error_words(job.error)}"
    waited = max(0, int((now - job.run_after).total_seconds()))  # since it was due (queued, or queued again)
    if waited < 10:
        return f"{noun[0].upper()}{noun[1:]} is queued; a worker will build it in a moment."
    return f"{noun[0].upper()}{noun[1:]} has waited {waited} s for a worker; is `coach-server worker` running?"


def ask(
    *, db_session: Session, kind: str, key: str, payload: dict[str, Any], noun: str, redo_done: bool = True
) -> Asked:
    """Queues the job `key` unless it is queued or running, and returns where it is; flushes.

    A job done whose result is gone (redo_done: a newer build replaced it) is queued afresh, unless its result says
    the file is `invalid` (it cannot be used, said at once); a failed one is queued for one more try while it has had
    fewer than ASK_ATTEMPTS, its last error kept for the words meanwhile.
    """
    job = db_session.scalar(select(Job).where(Job.key == key))
    invalid = job.result.get("invalid") if job is not None and job.status == "done" and job.result else None
    if invalid:  # the job found the stored file cannot be used: no try changes that
        return Asked("failed", f"The stored session file cannot be read: {invalid}", job)
    if job is None:
        enqueue(db_session=db_session, kind=kind, items=[(key, payload)])
        job = db_session.scalar(select(Job).where(Job.key == key))
    elif job.status == "done" and redo_done:
        again = {"status": "queued", "attempts": 0, "run_after": utcnow(), "error": None, "finished_at": None}
        db_session.execute(update(Job).where(Job.id == job.id, Job.status == "done").values(**again))
        db_session.refresh(job)
    elif job.status == "failed" and job.attempts < ASK_ATTEMPTS:
        again = {"status": "queued", "max_attempts": job.attempts + 1, "run_after": utcnow(), "finished_at": None}
        db_session.execute(update(Job).where(Job.id == job.id, Job.status == "failed").values(**again))
        db_session.refresh(job)
    if job is None:  # deleted between the insert and the read (an erasure): queued again on the next ask
        return Asked("preparing", f"{noun[0].upper()}{noun[1:]} is queued.", None)
    if job.status == "failed":
        words = error_words(job.error) or f"{noun[0].upper()}{noun[1:]} could not be built."
        return Asked("failed", f"{words} (tried {job.attempts} times)", job)
    return Asked("preparing", waiting_words(job, noun, utcnow()), job)
