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
from backend.i18n import ENGLISH, N_, Translator
from backend.jobs.listing import error_words
from backend.jobs.models import Job
from backend.jobs.queue import enqueue

ASK_ATTEMPTS = 6  # tries of one job in all, the queue's own retries and one more per ask after it failed


@dataclass(frozen=True)
class Asked:
    """Where the job of a result is: "preparing" (queued or running) or "failed" (for good); detail in words, in the
    language of the translator ask was given."""

    state: str
    detail: str
    job: Job | None


@dataclass(frozen=True)
class Words:
    """What one kind of result is told in, a whole sentence each (a noun put into a shared sentence does not
    translate: "the replay" and "the session's curves" change the words around them in German or French)."""

    building: str
    queued: str
    waited: str  # %(seconds)s
    not_built: str


# the patient opens the replay page too: these are in the `messages` catalogue, translated for every locale
WORDS = {
    "replay": Words(
        N_("A worker is building the replay."),
        N_("The replay is queued; a worker will build it in a moment."),
        N_("The replay has waited %(seconds)s s for a worker; is `coach-server worker` running?"),
        N_("The replay could not be built."),
    ),
    "detail": Words(
        N_("A worker is preparing the session's curves and numbers."),
        N_("The session's curves and numbers are queued; a worker will prepare them in a moment."),
        N_(
            "The session's curves and numbers have waited %(seconds)s s for a worker; is `coach-server worker` running?"
        ),
        N_("The session's curves and numbers could not be prepared."),
    ),
    "export": Words(  # %(file)s: the download's name, "motion (BVH)"
        N_("A worker is building the session's %(file)s file."),
        N_("The session's %(file)s file is queued; a worker will build it in a moment."),
        N_("The session's %(file)s file has waited %(seconds)s s for a worker; is `coach-server worker` running?"),
        N_("The session's %(file)s file could not be built."),
    ),
    "archive": Words(  # all of a patient's data in one zip (backend.records.prepared_archive)
        N_("A worker is making the archive of all the data."),
        N_("The archive of all the data is queued; a worker will make it in a moment."),
        N_("The archive of all the data has waited %(seconds)s s for a worker; is `coach-server worker` running?"),
        N_("The archive of all the data could not be made."),
    ),
}
_TRY_AGAIN = N_("The last try failed; a worker will try again. %(reason)s")
_UNREADABLE = N_("The stored session file cannot be read: %(reason)s")
_UNREADABLE_PLAIN = N_("The stored session file cannot be read.")


def waiting_words(job: Job, words: Words, now: dt.datetime, t: Translator = ENGLISH, **params: str) -> str:
    """Returns where a queued or running job is, in t's words (params: the words' placeholders but seconds)."""
    if job.status == "running":
        return t.gettext(words.building, **params)
    if job.error:
        return t.gettext(_TRY_AGAIN, reason=error_words(job.error, t) or "")
    waited = max(0, int((now - job.run_after).total_seconds()))  # since it was due (queued, or queued again)
    if waited < 10:
        return t.gettext(words.queued, **params)
    return t.gettext(words.waited, seconds=t.format_number(waited), **params)


def ask(
    *,
    db_session: Session,
    kind: str,
    key: str,
    payload: dict[str, Any],
    redo_done: bool = True,
    t: Translator = ENGLISH,
    params: dict[str, str] | None = None,
) -> Asked:
    """Queues the job `key` unless it is queued or running, and returns where it is; flushes.

    A job done whose result is gone (redo_done: a newer build replaced it) is queued afresh, unless its result says
    the file is `invalid` (it cannot be used, said at once); a failed one is queued for one more try while it has had
    fewer than ASK_ATTEMPTS, its last error kept for the words meanwhile. kind: one of WORDS, params its words'
    placeholders; t: the reader's language (the program's own words about a failure: a clinic's reader only,
    jobs.listing.error_words).
    """
    words, params = WORDS[kind], params or {}
    job = db_session.scalar(select(Job).where(Job.key == key))
    invalid = job.result.get("invalid") if job is not None and job.status == "done" and job.result else None
    if invalid:  # the job found the stored file cannot be used: no try changes that (its reason: for the clinic)
        said = t.gettext(_UNREADABLE, reason=invalid) if t.therapist else t.gettext(_UNREADABLE_PLAIN)
        return Asked("failed", said, job)
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
        return Asked("preparing", t.gettext(words.queued, **params), None)
    if job.status == "failed":
        said = error_words(job.error, t) or t.gettext(words.not_built, **params)
        return Asked("failed", t.ngettext("%(reason)s (tried once)", "%(reason)s (tried %(num)d times)",
                                          job.attempts, reason=said), job)  # fmt: skip
    return Asked("preparing", waiting_words(job, words, utcnow(), t, **params), job)
