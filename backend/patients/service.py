"""Patient listing and therapist assignment."""

from __future__ import annotations

from typing import TYPE_CHECKING

from sqlalchemy import Select, func, select
from sqlalchemy.orm import Session

from backend.database import utcnow
from backend.events.hub import ACCESS_ENDED, Event, publish
from backend.exceptions import TherapistNotFound
from backend.patients.models import TherapistPatient
from backend.users.models import User

if TYPE_CHECKING:
    from backend.deps import Caller


def therapist_ids_by_patient(*, db_session: Session, patient_ids: list[int]) -> dict[int, list[int]]:
    """Returns {patient id: ids of the therapists assigned to them} for many patients in one query."""
    out: dict[int, list[int]] = {pid: [] for pid in patient_ids}
    query = (
        select(TherapistPatient.patient_id, TherapistPatient.therapist_id)
        .where(TherapistPatient.patient_id.in_(patient_ids))
        .order_by(TherapistPatient.therapist_id)
    )
    for patient_id, therapist_id in db_session.execute(query):
        out[patient_id].append(therapist_id)
    return out


def therapist_ids(*, db_session: Session, patient_id: int) -> list[int]:
    """Returns the ids of the therapists assigned to a patient."""
    query = select(TherapistPatient.therapist_id).where(TherapistPatient.patient_id == patient_id)
    return sorted(db_session.scalars(query))


def visible_patients_query(caller: Caller) -> Select[User]:
    """Returns the select of patients the caller may see."""
    query = select(User).where(User.role == "patient")
    if caller.device is not None:
        return query.where(User.id == caller.device.patient_id)
    user = caller.signed_in_user
    if user.role == "patient":
        return query.where(User.id == user.id)
    if user.role == "therapist":
        assigned = select(TherapistPatient.patient_id).where(TherapistPatient.therapist_id == user.id)
        return query.where(User.id.in_(assigned))
    return query


def list_patients(*, db_session: Session, caller: Caller, limit: int, offset: int) -> tuple[list[User], int]:
    """Returns one page of the patients the caller may see, and the total."""
    query = visible_patients_query(caller)
    total = db_session.scalar(select(func.count()).select_from(query.subquery())) or 0
    return list(db_session.scalars(query.order_by(User.id).limit(limit).offset(offset))), total


def get_therapist(*, db_session: Session, therapist_id: int) -> User:
    """Returns an active therapist or raises TherapistNotFound."""
    user = db_session.get(User, therapist_id)
    if user is None or user.role != "therapist":
        raise TherapistNotFound(f"therapist {therapist_id} does not exist")
    return user


def assign(*, db_session: Session, patient: User, therapist: User) -> None:
    """Assigns a therapist to a patient (idempotent)."""
    key = {"therapist_id": therapist.id, "patient_id": patient.id}
    if db_session.get(TherapistPatient, key) is None:
        db_session.add(TherapistPatient(therapist_id=therapist.id, patient_id=patient.id, created_at=utcnow()))
        db_session.flush()


def unassign(*, db_session: Session, patient: User, therapist: User) -> None:
    """Removes a therapist from a patient (idempotent); the therapist's open event streams end, and reconnect to the
    patients they still have."""
    row = db_session.get(TherapistPatient, {"therapist_id": therapist.id, "patient_id": patient.id})
    if row is not None:
        db_session.delete(row)
        db_session.flush()
        publish(db_session, Event(ACCESS_ENDED, 0, {"user_id": therapist.id}))


def set_locale(*, db_session: Session, patient: User, locale: str | None) -> None:
    """Sets the language of a patient's pages (None: the browser's)."""
    patient.locale = locale
    db_session.flush()


def set_time_zone(*, db_session: Session, patient: User, time_zone: str | None) -> None:
    """Sets the IANA time zone of a patient's reminder times (None: the server's COACH_TIME_ZONE)."""
    patient.time_zone = time_zone
    db_session.flush()


def set_reminder_emails(*, db_session: Session, patient: User, on: bool) -> None:
    """Turns a patient's reminder e-mails on again or off (off keeps the first time they were stopped)."""
    if on:
        patient.reminder_emails_off_at = None
    elif patient.reminder_emails_off_at is None:
        patient.reminder_emails_off_at = utcnow()
    db_session.flush()


def set_pain_alert(*, db_session: Session, patient: User, above: int | None) -> None:
    """Sets the pain (0-9) above which the patient's answers after a set raise their attention (None: the default)."""
    patient.pain_alert_above = above
    db_session.flush()
