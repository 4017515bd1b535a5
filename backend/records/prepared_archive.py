"""A patient's archive built off the request path: once by a job-queue worker, kept in the object store.

Building the archive (backend.records.archive) reads every session file of the patient and exports each session:
0.1-1 s of CPU per session, minutes for a patient with years of data (bench/README.md), beyond a reverse proxy's
read timeout. So a request never builds it: it asks (`ask_archive`: queues the job `archive:<patient id>:<covers>`
once, whoever asks and however often) and answers where the build is; the worker (`run`) writes the zip to the
object store (content-addressed, sha256 checked on every read; written from a temporary file a chunk at a time, so a
build's memory does not grow with the archive) and points the patient's one `patient_archive` row
at it, replacing the one before (whose object is deleted after the commit). `covers` is the sha256 of the
patient's data the archive is made from (`covers_of`): a new session, a re-analysis, a new plan, advice or reply
makes the kept archive stale, and the next ask builds a new one. While it runs the job reports how many sessions
are written (`Job.result["progress"]`) and renews its lease, so a long build is neither shown as stuck nor taken
by a second worker. `coach-server patient-data archive` (backend.records.commands) asks the same way and then runs the
same job itself (`build_now`: claimed as a worker claims it, or waited for while a worker runs it), so an archive of
the same data is built and stored once, whether a worker, the command or both at once are on it.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import json
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from sqlalchemy import func, select, update
from sqlalchemy.orm import Session
from sqlalchemy.sql import ColumnElement, Executable

from backend.camera.models import CameraConsent, CameraSet
from backend.config import Settings
from backend.database import keep_row, utcnow
from backend.devices.models import Device
from backend.exceptions import ArchiveNotMade
from backend.feeling.models import SessionFeeling
from backend.i18n import ENGLISH, N_, Translator
from backend.jobs.asking import WORDS, ask, waiting_words
from backend.jobs.listing import error_words
from backend.jobs.models import Job, SessionMetricVersion
from backend.jobs.queue import LEASE
from backend.patients.models import TherapistPatient
from backend.plans.models import Plan, PlanItem
from backend.records.archive import FORMAT_VERSION, build_archive
from backend.records.erasure import delete_after_commit, unnamed_keys
from backend.records.models import PatientArchive
from backend.reminders.models import ReminderSent
from backend.replies.models import AdviceReply
from backend.sessions.models import ExerciseSession, SessionMetric
from backend.storage import get_store
from backend.suggestions.models import Suggestion
from backend.users.models import User
from backend.voice.models import VoicePreference

KIND = "archive"
PROGRESS_EVERY_S = 5.0  # how often a running build writes its progress and renews its lease
_NOT_MADE = N_("Your archive could not be made: %(reason)s")  # the patient reads it
_NOT_MADE_CLINIC = N_("The archive of this patient's data could not be made: %(reason)s")  # an admin reads it


@dataclass(frozen=True)
class ArchiveState:
    """Where a patient's archive is. state: "none" (never asked), "preparing" (queued or being built), "failed"
    (for good, `detail` says why) or "ready" (`kept` is the archive; `current` whether it covers today's data).
    detail: in the reader's words; progress: sessions written and in all while it is built."""

    state: str
    detail: str
    kept: PatientArchive | None = None
    current: bool = False
    progress: tuple[int, int] | None = None
    job: Job | None = None  # the build's job, as ask_archive found or queued it


def _rows(db_session: Session, query: Executable) -> list[list[Any]]:
    return [list(r) for r in db_session.execute(query).all()]


def _changes(db_session: Session, where: ColumnElement[bool], *columns: Any) -> list[list[Any]]:
    """Returns [[count, max of each column]] of the rows `where` selects: what changes when a row is added or edited."""
    return _rows(db_session, select(func.count(), *(func.max(c) for c in columns)).where(where))


def covers_of(*, db_session: Session, patient: User) -> str:
    """Returns the sha256 (64 hex digits) of what the patient's archive is made from: the account, each session
    (file, status, metrics, how it felt), the metrics a re-analysis replaced, the plans, therapists, advice,
    replies, devices, settings, camera sets, reminders and FORMAT_VERSION. The audit log is left out (every ask
    adds to it). A few aggregate queries: no document or file is read."""
    pid = patient.id
    sessions = (
        select(ExerciseSession.id, ExerciseSession.content_hash, ExerciseSession.file_key, ExerciseSession.status,
               ExerciseSession.processing_version, SessionMetric.id, SessionFeeling.updated_at)
        .outerjoin(SessionMetric, SessionMetric.session_id == ExerciseSession.id)
        .outerjoin(SessionFeeling, SessionFeeling.session_id == ExerciseSession.id)
        .where(ExerciseSession.patient_id == pid)
        .order_by(ExerciseSession.id)
    )  # fmt: skip
    own_sessions = select(ExerciseSession.id).where(ExerciseSession.patient_id == pid)
    own_plans = select(Plan.id).where(Plan.patient_id == pid)
    what: dict[str, Any] = {
        "version": FORMAT_VERSION,
        "account": [patient.email, patient.full_name, patient.locale, patient.is_active, str(patient.deactivated_at)],
        "sessions": _rows(db_session, sessions),
        "earlier": _changes(db_session, SessionMetricVersion.session_id.in_(own_sessions), SessionMetricVersion.id),
        "plans": _changes(db_session, Plan.patient_id == pid, Plan.id, Plan.updated_at),
        "items": _changes(db_session, PlanItem.plan_id.in_(own_plans), PlanItem.id),
        "therapists": _changes(db_session, TherapistPatient.patient_id == pid, TherapistPatient.therapist_id),
        "advice": _changes(db_session, Suggestion.patient_id == pid, Suggestion.id, Suggestion.decided_at),
        "replies": _changes(db_session, AdviceReply.patient_id == pid, AdviceReply.id, AdviceReply.read_at),
        "devices": _rows(
            db_session, select(Device.id, Device.name).where(Device.patient_id == pid).order_by(Device.id)
        ),
        "voice": _changes(db_session, VoicePreference.patient_id == pid, VoicePreference.updated_at),
        "consent": _changes(db_session, CameraConsent.patient_id == pid, CameraConsent.given_at),
        "camera_sets": _changes(db_session, CameraSet.patient_id == pid, CameraSet.started_at, CameraSet.ended_at),
        "reminders": _changes(db_session, ReminderSent.patient_id == pid, ReminderSent.id),
    }
    text = json.dumps(what, sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def job_key(patient_id: int, covers: str) -> str:
    """Returns the queue key of the build of a patient's archive covering `covers` (covers_of)."""
    return f"{KIND}:{patient_id}:{covers}"


def kept_archive(*, db_session: Session, patient_id: int) -> PatientArchive | None:
    """Returns the patient's kept archive row (the last one built), or None."""
    return db_session.scalar(select(PatientArchive).where(PatientArchive.patient_id == patient_id))


def _progress(job: Job | None) -> tuple[int, int] | None:
    """Returns (sessions written, sessions in all) a running build last reported, or None."""
    found = job.result.get("progress") if job is not None and job.status == "running" and job.result else None
    return (int(found["done"]), int(found["total"])) if isinstance(found, dict) else None


def archive_state(*, db_session: Session, patient: User, t: Translator = ENGLISH) -> ArchiveState:
    """Returns where the patient's archive is, queueing nothing: the kept archive when it covers today's data, else
    its build's state when one was asked for today's data, else the kept (stale) archive, else "none"."""
    covers = covers_of(db_session=db_session, patient=patient)
    kept = kept_archive(db_session=db_session, patient_id=patient.id)
    if kept is not None and kept.covers == covers:
        return ArchiveState("ready", "", kept, current=True)
    job = db_session.scalar(select(Job).where(Job.key == job_key(patient.id, covers)))
    if job is not None and job.status in ("queued", "running", "failed"):
        return job_state(job, t, kept)
    if kept is not None:
        return ArchiveState("ready", "", kept, current=False)
    return ArchiveState("none", "")


def _not_made(t: Translator, reason: str) -> str:
    """Returns why the archive is not made, worded for its reader: the patient ("your"), or an admin of the clinic
    (t.therapist: the translator of a therapist's or admin's request, backend.i18n.reader_translator)."""
    return t.gettext(_NOT_MADE_CLINIC if t.therapist else _NOT_MADE, reason=reason)


def job_state(job: Job, t: Translator, kept: PatientArchive | None) -> ArchiveState:
    """Returns where a queued, running or failed build is, in the words an ask gives (jobs.asking)."""
    if job.status == "failed":
        reason = error_words(job.error, t) or t.gettext(WORDS[KIND].not_built)
        return ArchiveState("failed", _not_made(t, reason), kept)
    return ArchiveState("preparing", waiting_words(job, WORDS[KIND], utcnow(), t), kept, progress=_progress(job))


def ask_archive(*, db_session: Session, patient: User, requested_by: str, t: Translator = ENGLISH) -> ArchiveState:
    """Returns the patient's archive when the kept one covers today's data; else queues its build unless it is
    queued or running (a failed one is tried again, up to jobs.asking.ASK_ATTEMPTS tries) and returns where it is.
    Flushes. requested_by: who asked, as the README says it ("the patient", "admin x@clinic.org")."""
    covers = covers_of(db_session=db_session, patient=patient)
    kept = kept_archive(db_session=db_session, patient_id=patient.id)
    if kept is not None and kept.covers == covers:
        return ArchiveState("ready", "", kept, current=True)
    asked = ask(db_session=db_session, kind=KIND, key=job_key(patient.id, covers),
                payload={"patient_id": patient.id, "requested_by": requested_by}, t=t)  # fmt: skip
    if asked.state == "failed":
        return ArchiveState("failed", _not_made(t, asked.detail), kept)
    return ArchiveState("preparing", asked.detail, kept, progress=_progress(asked.job), job=asked.job)


def read_archive(archive: PatientArchive) -> bytes:
    """Returns the kept archive's zip, read from the object store with its sha256 checked (raises StorageError when
    missing or corrupt)."""
    return get_store().get(archive.data_key, archive.data_hash)


def archive_chunks(archive: PatientArchive) -> Iterator[bytes]:
    """Returns the kept archive's zip as chunks to send (ObjectStore.stream): missing, or corrupt where the store
    checks before sending (local), raises here; corrupt on S3 raises StoredObjectCorrupt after the last chunk."""
    return get_store().stream(archive.data_key, archive.data_hash)


def copy_archive(archive: PatientArchive, path: Path) -> int:
    """Writes the kept archive's zip to path a chunk at a time; path is replaced only once the sha256 is checked
    (raises StorageError when missing or corrupt, leaving path as it was). Returns its size in bytes."""
    return get_store().copy_to(archive.data_key, archive.data_hash, path)


def progress_reporter(db_session: Session, job_id: int | None) -> Callable[[int, int], None]:
    """Returns progress(done, total): every PROGRESS_EVERY_S (and at the start) writes it on the job and renews the
    job's lease, committing (the build itself writes nothing until it stores the zip)."""
    last = [float("-inf")]

    def progress(done: int, total: int) -> None:
        if job_id is None or time.monotonic() - last[0] < PROGRESS_EVERY_S:
            return
        last[0] = time.monotonic()
        db_session.execute(update(Job).where(Job.id == job_id, Job.status == "running").values(
            result={"progress": {"done": done, "total": total}}, locked_until=utcnow() + LEASE))  # fmt: skip
        db_session.commit()

    return progress


def run(*, db_session: Session, patient_id: int, requested_by: str, settings: Settings,
        job_id: int | None = None) -> dict[str, Any]:  # fmt: skip
    """Runs the job of a patient's archive: builds it (unless the kept one covers today's data), stores the zip and
    points the patient's patient_archive row at it; the archive it replaces is deleted once the job commits. Nothing
    is kept when the build fails: the object is written (atomically) once the zip is complete, its row after it."""
    patient = db_session.get(User, patient_id)
    if patient is None:
        return {"patient_id": patient_id, "built": False, "skipped": "the patient no longer exists"}
    covers = covers_of(db_session=db_session, patient=patient)
    done: dict[str, Any] = {"patient_id": patient_id, "built": False, "covers": covers}
    before = kept_archive(db_session=db_session, patient_id=patient_id)
    if before is not None and before.covers == covers:
        return done
    old_key = before.data_key if before is not None else None
    made_at = dt.datetime.now(dt.UTC)
    built = build_archive(db_session=db_session, patient=patient, requested_by=requested_by, settings=settings,
                          progress=progress_reporter(db_session, job_id), made_at=made_at)  # fmt: skip
    try:
        obj = get_store().put_file(KIND, built.file)  # streamed from the spooled file: never all of it in memory
    finally:
        built.file.close()
    # The build wrote nothing: end its long read transaction before writing. On SQLite (WAL) a transaction whose
    # snapshot predates another connection's commit cannot become a writer ("database is locked" at once, whatever
    # the busy timeout): a request's audit row written during the build would fail it, and a second try build again.
    db_session.commit()
    name = f"patient-{patient_id}-data-{made_at:%Y%m%d}.zip"
    try:
        keep_row(db_session, PatientArchive, {"patient_id": patient_id},
                 {"covers": covers, "sessions": built.sessions, "incomplete": len(built.incomplete),
                  "data_key": obj.key, "data_hash": obj.sha256, "size": obj.size, "file_name": name,
                  "made_at": made_at})  # fmt: skip
        db_session.flush()
    except Exception:  # no row names the object: it goes, rather than wait in the store for `storage check`
        db_session.rollback()
        if unnamed_keys(db_session, {obj.key}):
            get_store().delete(obj.key)
        raise
    stale = {k for k in (old_key,) if k and k != obj.key}
    if kept_archive(db_session=db_session, patient_id=patient_id) is None:  # erased meanwhile: nothing may stay
        stale.add(obj.key)
    delete_after_commit(db_session, unnamed_keys(db_session, stale))
    return done | {
        "built": True,
        "size": obj.size,
        "sessions": built.sessions,
        "incomplete": len(built.incomplete),
        "incomplete_sessions": list(built.incomplete),
    }


def build_now(*, db_session: Session, patient: User, requested_by: str, settings: Settings, name: str,
              poll_s: float = 0.5) -> dict[str, Any]:  # fmt: skip
    """Returns the result of the patient's archive job (run's) once the kept archive covers today's data ("built":
    whether it was built now, here or by a worker, rather than kept from before): asks as a request does
    (ask_archive, committed), then runs the job here unless a worker holds it, and then waits for that worker
    (backend.jobs.worker.run_here_or_wait). Commits; raises ArchiveNotMade when the build failed for good.
    name: who runs it, as a worker is named (the job's locked_by while it runs)."""
    from backend.jobs.worker import run_here_or_wait

    asked = ask_archive(db_session=db_session, patient=patient, requested_by=requested_by)
    db_session.commit()
    if asked.state == "ready":
        return {"patient_id": patient.id, "built": False}
    if asked.state == "failed" or asked.job is None:
        raise ArchiveNotMade(asked.detail or WORDS[KIND].not_built)
    job = run_here_or_wait(db_session=db_session, key=asked.job.key, settings=settings, name=name, poll_s=poll_s)
    if job is None or job.status != "done":
        why = error_words(job.error, ENGLISH) if job is not None and job.error else None
        raise ArchiveNotMade(why or WORDS[KIND].not_built)
    return dict(job.result or {})
