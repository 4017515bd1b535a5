"""What the admin page shows of the queue: batches with their progress, recent jobs, and each failure in words.

A job's `error` column keeps the exception's class, message and a short traceback for the logs; people get one
sentence (`error_words`) in their language: what went wrong with that session and what it means, never a traceback.
A failed session's `error` (`AnalysisError: ...`) is said the same way.
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass

from sqlalchemy import func, select
from sqlalchemy.orm import Session

from backend.audit.models import AuditEvent
from backend.i18n import N_, Translator
from backend.jobs.models import Job

# the exception classes a job (or a session's analysis) meets, said for people; in the `messages` catalogue: a
# patient reads why their replay or session failed
_KNOWN = {
    "SessionFileRemoved": N_("The session's recording was removed under the clinic's retention policy"),
    "StoredObjectMissing": N_("The session's file is missing from the object store"),
    "StoredObjectCorrupt": N_("The session's file in the object store is damaged: its checksum does not match"),
    "SessionFileError": N_("The stored session file cannot be read"),
    "InvalidSessionFile": N_("The stored session file cannot be read"),
    "AnalysisError": N_("The analysis could not use this recording"),
    "RecordingNotFilterable": N_(
        "Today's pipeline cannot filter the session's raw recording; the session is unchanged"
    ),
}
_HINTS = {"StoredObjectMissing": " (run `coach-server storage check`)"}  # for the clinic, after the sentence
_FAILED = N_("The job failed")
_UNEXPECTED = N_("The job failed on an unexpected error")
_NAMED = N_("%(what)s (%(name)s)")  # TRANSLATORS: an unexpected error and its exception's name, for the clinic
_DETAILED = N_("%(what)s: %(detail)s")  # TRANSLATORS: what failed, then the program's own words (English)
_SENTENCE = N_("%(what)s.")  # TRANSLATORS: what failed, as a sentence
_NO_REASON = N_("no reason was recorded")
_STATES = ("queued", "running", "done", "failed")
CLINIC_ENGLISH = Translator("en", therapist=True)  # the admin page: English, the program's words included


def error_words(error: str | None, t: Translator = CLINIC_ENGLISH) -> str | None:
    """Returns a job's or a session's error (`Class: message`, a traceback after it) as one sentence in t's
    language; None when there is none. The message after the class is the program's own (English): only a clinic's
    reader (t.therapist: a therapist or admin) gets it, and the name of an unexpected class; a patient gets the
    sentence alone, never a traceback."""
    if not error:
        return None
    first = error.strip().splitlines()[0] if error.strip() else ""
    name, _, message = first.partition(": ")
    if not message or " " in name:  # not "Class: message": said as it is, to the clinic
        what, name, message = _FAILED, "", first or t.gettext(_NO_REASON)
    else:
        what = _KNOWN.get(name, _UNEXPECTED)
    head = t.gettext(what)
    if not t.therapist:
        return t.gettext(_SENTENCE, what=head)
    if what == _UNEXPECTED:
        head = t.gettext(_NAMED, what=head, name=name)
    return t.gettext(_DETAILED, what=head + _HINTS.get(name, ""), detail=message)


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
