"""What the admin page shows of the queue: batches with their progress, recent jobs, and each failure in words.

A job's `error` column keeps the exception's class, message and a short traceback for the logs; people get one
sentence (`error_words`): what went wrong with that session and what it means, never a traceback.
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass

from sqlalchemy import func, select
from sqlalchemy.orm import Session

from backend.audit.models import AuditEvent
from backend.jobs.models import Job

# the exception classes a job meets on stored sessions, said for people (the message follows in brackets)
_KNOWN = {
    "SessionFileRemoved": "The session's recording was removed under the clinic's retention policy",
    "StoredObjectMissing": "The session's file is missing from the object store (run `coach-server storage check`)",
    "StoredObjectCorrupt": "The session's file in the object store is damaged: its checksum does not match",
    "SessionFileError": "The stored session file cannot be read",
    "InvalidSessionFile": "The stored session file cannot be read",
    "AnalysisError": "The analysis could not use this recording",
    "RecordingNotFilterable": "Today's pipeline cannot filter the session's raw recording; the session is unchanged",
}
_STATES = ("queued", "running", "done", "failed")


def error_words(error: str | None) -> str | None:
    """Returns a job's error (`Class: message` + traceback) as one sentence for people; None when there is none."""
    if not error:
        return None
    first = error.strip().splitlines()[0] if error.strip() else ""
    name, _, message = first.partition(": ")
    if not message or " " in name:  # not "Class: message": say it as it is
        return f"The job failed: {first or 'no reason was recorded'}"
    head = _KNOWN.get(name, f"The job failed on an unexpected error ({name})")
    return f"{head}: {message}" if message else head


@dataclass(frozen=True)
class BatchRow:
    """One batch of jobs queued together: counts per state, who queued it and what for, when it began and ended."""

    batch: str
    kind: str
    queued: int
    running: int
    done: int
    failed: int
    total: int
    created_at: dt.datetime
    finished_at: dt.datetime | None  # the last job's end, once none is queued or running
    queued_by: int | None  # the user id of the audit row that queued it
    patient_id: int | None  # the one patient it is about (None: all patients)


def list_batches(*, db_session: Session, kind: str, limit: int) -> list[BatchRow]:
    """Returns the newest `limit` batches of jobs of `kind`, newest first, with their progress."""
    newest = (
        select(Job.batch, func.min(Job.created_at).label("created_at"), func.max(Job.finished_at).label("finished"))
        .where(Job.kind == kind, Job.batch.is_not(None))
        .group_by(Job.batch)
        .order_by(func.min(Job.created_at).desc(), Job.batch.desc())
        .limit(limit)
    )
    heads = db_session.execute(newest).all()
    names = [h.batch for h in heads]
    counts: dict[str, dict[str, int]] = {name: dict.fromkeys(_STATES, 0) for name in names}
    for batch, state, n in db_session.execute(
        select(Job.batch, Job.status, func.count()).where(Job.batch.in_(names)).group_by(Job.batch, Job.status)
    ):
        if batch is not None:  # in names: never None
            counts[batch][state] = int(n)
    who = {
        a.object_id: a
        for a in db_session.scalars(
            select(AuditEvent).where(AuditEvent.object_type == "batch", AuditEvent.object_id.in_(names))
        )
    }
    rows = []
    for head in heads:
        c = counts[head.batch]
        audit = who.get(head.batch)
        busy = c["queued"] + c["running"] > 0
        rows.append(BatchRow(batch=head.batch, kind=kind, **c, total=sum(c.values()), created_at=head.created_at,
                             finished_at=None if busy else head.finished, queued_by=audit.actor_user_id if audit
                             else None, patient_id=audit.patient_id if audit else None))  # fmt: skip
    return rows


def list_jobs(*, db_session: Session, batch: str | None, status: str | None, limit: int) -> list[Job]:
    """Returns the newest `limit` jobs (of one batch, in one state, when given), newest first."""
    query = select(Job)
    if batch is not None:
        query = query.where(Job.batch == batch)
    if status is not None:
        query = query.where(Job.status == status)
    return list(db_session.scalars(query.order_by(Job.id.desc()).limit(limit)))
