"""Patients: list the ones the caller may see, read one, and (admin) assign therapists."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, status
from sqlalchemy.orm import Session

from backend.audit.service import record, record_patients
from backend.deps import AdminCaller, CurrentCaller, DbSession, require_patient_access
from backend.exceptions import (
    AUTH_ERRORS,
    Forbidden,
    PatientNotFound,
    TherapistNotFound,
    error_responses,
)
from backend.patients import service
from backend.patients.schemas import PatientOut, PatientUpdate
from backend.schemas import IdPath, Page, PageParams, page_params
from backend.sessions.triage import PAIN_ALERT_ABOVE
from backend.users.models import User
from backend.users.schemas import UserOut

router = APIRouter(prefix="/api/v1/patients", tags=["patients"])


def _out(db_session: Session, patient: User, therapist_ids: list[int] | None = None) -> PatientOut:
    if therapist_ids is None:
        therapist_ids = service.therapist_ids(db_session=db_session, patient_id=patient.id)
    return PatientOut(
        id=patient.id,
        email=patient.email,
        full_name=patient.full_name,
        is_active=patient.is_active,
        created_at=patient.created_at,
        therapist_ids=therapist_ids,
        locale=patient.locale,
        time_zone=patient.time_zone,
        reminder_emails=patient.reminder_emails_off_at is None,
        pain_alert_above=PAIN_ALERT_ABOVE if patient.pain_alert_above is None else patient.pain_alert_above,
    )


@router.get("", response_model=Page[PatientOut], responses=error_responses(*AUTH_ERRORS))
def list_patients(
    caller: CurrentCaller, db_session: DbSession, page: Annotated[PageParams, Depends(page_params)]
) -> Page[PatientOut]:
    """Lists the patients the caller may see: admins all, therapists assigned ones, patients themselves."""
    rows, total = service.list_patients(db_session=db_session, caller=caller, limit=page.limit, offset=page.offset)
    ids = [p.id for p in rows]
    record_patients(db_session=db_session, caller=caller, action="patient.list", object_type="patient", patient_ids=ids)
    therapists = service.therapist_ids_by_patient(db_session=db_session, patient_ids=ids)
    return Page[PatientOut](
        items=[_out(db_session, p, therapists[p.id]) for p in rows], total=total, limit=page.limit, offset=page.offset
    )


@router.get("/{patient_id}", response_model=PatientOut, responses=error_responses(*AUTH_ERRORS, PatientNotFound))
def get_patient(patient_id: IdPath, caller: CurrentCaller, db_session: DbSession) -> PatientOut:
    """Returns one patient the caller may see."""
    patient = require_patient_access(patient_id, caller=caller, db_session=db_session)
    record(
        db_session=db_session,
        caller=caller,
        action="patient.read",
        object_type="patient",
        object_id=patient_id,
        patient_id=patient_id,
    )
    return _out(db_session, patient)


@router.patch(
    "/{patient_id}", response_model=PatientOut, responses=error_responses(*AUTH_ERRORS, PatientNotFound, Forbidden)
)
def update_patient(patient_id: IdPath, body: PatientUpdate, caller: CurrentCaller, db_session: DbSession) -> PatientOut:
    """Changes a patient's settings: the language of their pages, the time zone of their reminders and reminder
    e-mails on or off (the patient, their therapists, admins), and the pain alert level (their therapists and admins
    only)."""
    patient = require_patient_access(patient_id, caller=caller, db_session=db_session, write=True)
    given = body.model_fields_set
    if "pain_alert_above" in given and caller.role not in ("therapist", "admin"):
        raise Forbidden("only a therapist sets the pain alert level")
    if "locale" in given:
        service.set_locale(db_session=db_session, patient=patient, locale=body.locale)
    if "time_zone" in given:
        service.set_time_zone(db_session=db_session, patient=patient, time_zone=body.time_zone)
    if body.reminder_emails is not None:
        service.set_reminder_emails(db_session=db_session, patient=patient, on=body.reminder_emails)
    if "pain_alert_above" in given:
        service.set_pain_alert(db_session=db_session, patient=patient, above=body.pain_alert_above)
    record(
        db_session=db_session,
        caller=caller,
        action="patient.update",
        object_type="patient",
        object_id=patient_id,
        patient_id=patient_id,
        detail={k: getattr(body, k) for k in sorted(given)},
    )
    return _out(db_session, patient)


@router.get(
    "/{patient_id}/therapists", response_model=Page[UserOut], responses=error_responses(*AUTH_ERRORS, PatientNotFound)
)
def list_therapists(
    patient_id: IdPath, caller: CurrentCaller, db_session: DbSession, page: Annotated[PageParams, Depends(page_params)]
) -> Page[UserOut]:
    """Lists the therapists assigned to a patient."""
    require_patient_access(patient_id, caller=caller, db_session=db_session)
    ids = service.therapist_ids(db_session=db_session, patient_id=patient_id)
    chosen = ids[page.offset : page.offset + page.limit]
    record(
        db_session=db_session,
        caller=caller,
        action="patient.therapists.read",
        object_type="patient",
        object_id=patient_id,
        patient_id=patient_id,
    )
    return Page[UserOut](
        items=[UserOut.model_validate(db_session.get(User, i)) for i in chosen],
        total=len(ids),
        limit=page.limit,
        offset=page.offset,
    )


@router.put(
    "/{patient_id}/therapists/{therapist_id}",
    status_code=status.HTTP_204_NO_CONTENT,
    responses=error_responses(*AUTH_ERRORS, PatientNotFound, TherapistNotFound),
)
def assign_therapist(patient_id: IdPath, therapist_id: IdPath, caller: AdminCaller, db_session: DbSession) -> None:
    """Assigns a therapist to a patient (admin only)."""
    patient = require_patient_access(patient_id, caller=caller, db_session=db_session)
    therapist = service.get_therapist(db_session=db_session, therapist_id=therapist_id)
    service.assign(db_session=db_session, patient=patient, therapist=therapist)
    record(
        db_session=db_session,
        caller=caller,
        action="patient.assign",
        object_type="therapist_patient",
        object_id=f"{therapist_id}:{patient_id}",
        patient_id=patient_id,
    )


@router.delete(
    "/{patient_id}/therapists/{therapist_id}",
    status_code=status.HTTP_204_NO_CONTENT,
    responses=error_responses(*AUTH_ERRORS, PatientNotFound, TherapistNotFound),
)
def unassign_therapist(patient_id: IdPath, therapist_id: IdPath, caller: AdminCaller, db_session: DbSession) -> None:
    """Removes a therapist from a patient (admin only)."""
    patient = require_patient_access(patient_id, caller=caller, db_session=db_session)
    therapist = service.get_therapist(db_session=db_session, therapist_id=therapist_id)
    service.unassign(db_session=db_session, patient=patient, therapist=therapist)
    record(
        db_session=db_session,
        caller=caller,
        action="patient.unassign",
        object_type="therapist_patient",
        object_id=f"{therapist_id}:{patient_id}",
        patient_id=patient_id,
    )
