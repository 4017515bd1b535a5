"""Erasing a patient: every row about them and every stored object of theirs goes; the audit log keeps only that
an erasure happened, by whom and when."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

from sqlalchemy import Select, delete, event, func, or_, select, update
from sqlalchemy.engine import CursorResult
from sqlalchemy.orm import Session
from sqlalchemy.sql import Executable

from backend.audit.models import AuditEvent
from backend.audit.service import record
from backend.devices.models import Device, PairingCode
from backend.jobs.models import Job, SessionMetricVersion
from backend.patients.models import TherapistPatient
from backend.plans.models import Plan, PlanItem
from backend.records.models import PatientArchive
from backend.replay.models import SessionReplay
from backend.replies.models import AdviceReply
from backend.sessions.models import ExerciseSession, SessionDetail, SessionExport, SessionMetric
from backend.storage import get_store
from backend.suggestions.models import Suggestion
from backend.users.models import ApiToken, LoginAttempt, LoginSession, User

if TYPE_CHECKING:
    from backend.deps import Caller


@dataclass
class Erasure:
    """What an erasure removed: rows per table and the stored objects to delete once the transaction commits."""

    rows: dict[str, int]
    objects: list[str]


def _count(db_session: Session, stmt: Executable) -> int:
    return int(cast("CursorResult[Any]", db_session.execute(stmt)).rowcount or 0)  # a DELETE's result


def erase_patient(*, db_session: Session, patient: User, caller: Caller) -> Erasure:
    """Deletes every row about `patient` (sessions, metrics, replays, plans, advice, devices, links, logins,
    tokens, audit entries about or by them, their built archive, the account) and records one audit row
    "patient.erase" with no patient id, name or e-mail. The stored objects are deleted after the transaction
    commits (a rollback keeps them); an object another patient's row still points to is kept. Flushes, never commits."""
    pid, email = patient.id, patient.email
    session_ids = select(ExerciseSession.id).where(ExerciseSession.patient_id == pid)
    own_files = select(ExerciseSession.file_key).where(ExerciseSession.patient_id == pid)
    own_replays = select(SessionReplay.data_key).where(SessionReplay.session_id.in_(session_ids))
    own_details = select(SessionDetail.data_key).where(SessionDetail.session_id.in_(session_ids))
    keys = {k for k in db_session.scalars(own_files) if k} | {k for k in db_session.scalars(own_replays) if k}
    own_exports = select(SessionExport.data_key).where(SessionExport.session_id.in_(session_ids))
    keys |= set(db_session.scalars(own_details)) | set(db_session.scalars(own_exports))
    keys |= earlier_file_keys(db_session, session_ids)
    keys |= set(db_session.scalars(select(PatientArchive.data_key).where(PatientArchive.patient_id == pid)))
    rows = {
        "session_replay": _count(db_session, delete(SessionReplay).where(SessionReplay.session_id.in_(session_ids))),
        "session_detail": _count(db_session, delete(SessionDetail).where(SessionDetail.session_id.in_(session_ids))),
        "session_export": _count(db_session, delete(SessionExport).where(SessionExport.session_id.in_(session_ids))),
        "session_metric": _count(db_session, delete(SessionMetric).where(SessionMetric.session_id.in_(session_ids))),
        "session_metric_version": _count(
            db_session, delete(SessionMetricVersion).where(SessionMetricVersion.session_id.in_(session_ids))
        ),
        "advice_reply": _count(db_session, delete(AdviceReply).where(AdviceReply.patient_id == pid)),
        "suggestion": _count(db_session, delete(Suggestion).where(Suggestion.patient_id == pid)),
        # queued or finished work on their sessions (replay and detail builds, re-analysis): nothing may name them
        # afterwards
        "job": _count(db_session, delete(Job).where(Job.payload["session_id"].as_integer().in_(session_ids))),
        # their archive and its build (asked, running or done): a build that finishes after this keeps nothing
        "patient_archive": _count(db_session, delete(PatientArchive).where(PatientArchive.patient_id == pid)),
    }
    rows["job"] += _count(db_session, delete(Job).where(Job.kind == "archive",
                                                         Job.payload["patient_id"].as_integer() == pid))  # fmt: skip
    rows["exercise_session"] = _count(db_session, delete(ExerciseSession).where(ExerciseSession.patient_id == pid))
    plan_ids = select(Plan.id).where(Plan.patient_id == pid)
    rows["plan_item"] = _count(db_session, delete(PlanItem).where(PlanItem.plan_id.in_(plan_ids)))
    rows["plan"] = _count(db_session, delete(Plan).where(Plan.patient_id == pid))
    rows["pairing_code"] = _count(db_session, delete(PairingCode).where(PairingCode.patient_id == pid))
    rows["device"] = _count(db_session, delete(Device).where(Device.patient_id == pid))
    rows["therapist_patient"] = _count(db_session, delete(TherapistPatient).where(TherapistPatient.patient_id == pid))
    rows["api_token"] = _count(db_session, delete(ApiToken).where(ApiToken.user_id == pid))
    rows["login_session"] = _count(db_session, delete(LoginSession).where(LoginSession.user_id == pid))
    rows["login_attempt"] = _count(
        db_session, delete(LoginAttempt).where(func.lower(LoginAttempt.email) == email.lower())
    )
    about = or_(AuditEvent.patient_id == pid, AuditEvent.actor_user_id == pid,
                (AuditEvent.object_type.in_(("user", "patient"))) & (AuditEvent.object_id == str(pid)))  # fmt: skip
    rows["audit_event"] = _count(db_session, delete(AuditEvent).where(about))
    # rows of others that named the patient as author or decider (a patient never is, but the schema allows it)
    db_session.execute(update(Suggestion).where(Suggestion.author_id == pid).values(author_id=None))
    db_session.execute(update(Suggestion).where(Suggestion.decided_by_id == pid).values(decided_by_id=None))
    db_session.execute(update(PairingCode).where(PairingCode.created_by_id == pid).values(created_by_id=None))
    db_session.execute(update(AdviceReply).where(AdviceReply.read_by_id == pid).values(read_by_id=None))
    db_session.expunge(patient)
    rows["user"] = _count(db_session, delete(User).where(User.id == pid))
    objects = unnamed_keys(db_session, keys)
    record(db_session=db_session, caller=caller, action="patient.erase", object_type="patient",
           detail={"rows_deleted": sum(rows.values()), "objects_deleted": len(objects)})  # fmt: skip
    delete_after_commit(db_session, objects)
    return Erasure(rows=rows, objects=objects)


def earlier_file_keys(db_session: Session, session_ids: Select[Any] | list[int]) -> set[str]:
    """Returns the object keys of the earlier session files of these sessions (session_metric_version.file_key: the
    files a re-analysis with the pipeline replaced)."""
    query = select(SessionMetricVersion.file_key).where(SessionMetricVersion.session_id.in_(session_ids),
                                                        SessionMetricVersion.file_key.is_not(None))  # fmt: skip
    return {k for k in db_session.scalars(query) if k}


def unnamed_keys(db_session: Session, keys: set[str]) -> list[str]:
    """Returns, sorted, those of the object `keys` that no row names any more (session file, replay, detail, export,
    earlier session file, patient's archive): the objects that may be deleted once the transaction commits
    (delete_after_commit)."""
    named: set[str] = set()
    for column in (ExerciseSession.file_key, SessionReplay.data_key, SessionDetail.data_key, SessionExport.data_key,
                   SessionMetricVersion.file_key, PatientArchive.data_key):  # fmt: skip
        named |= set(db_session.scalars(select(column).where(column.in_(keys))))
    return sorted(keys - named)


_PENDING = "records.objects_to_delete"


def delete_after_commit(db_session: Session, keys: list[str]) -> None:
    """Deletes the objects once the session's transaction commits; nothing when it rolls back."""
    if keys:
        db_session.info.setdefault(_PENDING, []).extend(keys)


@event.listens_for(Session, "after_commit")
def _on_commit(session: Session) -> None:
    keys = session.info.pop(_PENDING, None)
    if keys:
        store = get_store()
        for key in keys:
            store.delete(key)


@event.listens_for(Session, "after_rollback")
def _on_rollback(session: Session) -> None:
    session.info.pop(_PENDING, None)
