"""Reminders: a patient's reminders today, and the unsubscribe link of a reminder e-mail (no login)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Path, Request

from backend.audit.service import record
from backend.database import utcnow
from backend.deps import CurrentCaller, DbSession, require_patient_access
from backend.exceptions import AUTH_ERRORS, PatientNotFound, UnsubscribeLinkUnknown, error_responses
from backend.reminders import service
from backend.reminders.schemas import RemindersOut, UnsubscribedOut
from backend.schemas import IdPath

router = APIRouter(prefix="/api/v1", tags=["reminders"])

UnsubscribeToken = Annotated[str, Path(min_length=10, max_length=100, pattern=r"^[A-Za-z0-9_-]+$",
                                       description="the token of a reminder e-mail's unsubscribe link")]  # fmt: skip


@router.get(
    "/patients/{patient_id}/reminders",
    response_model=RemindersOut,
    responses=error_responses(*AUTH_ERRORS, PatientNotFound),
)
def get_reminders(patient_id: IdPath, caller: CurrentCaller, db_session: DbSession, request: Request) -> RemindersOut:
    """Returns the patient's reminder times today (in their time zone, from the plan running today) and the next."""
    patient = require_patient_access(patient_id, caller=caller, db_session=db_session)
    return service.today(db_session=db_session, patient=patient, settings=request.app.state.settings, now=utcnow())


@router.post(
    "/reminders/unsubscribe/{token}",
    response_model=UnsubscribedOut,
    responses=error_responses(UnsubscribeLinkUnknown),
)
def unsubscribe(token: UnsubscribeToken, db_session: DbSession) -> UnsubscribedOut:
    """Stops the reminder e-mails of the patient a reminder e-mail went to; needs no login (the token is the
    e-mail's), and using it again changes nothing."""
    patient = service.unsubscribe(db_session=db_session, token=token)
    record(db_session=db_session, caller=None, action="reminders.unsubscribe", object_type="patient",
           object_id=patient.id, patient_id=patient.id)  # fmt: skip
    assert patient.reminder_emails_off_at is not None
    return UnsubscribedOut(unsubscribed=True, since=patient.reminder_emails_off_at)
