"""How a set felt: the patient answers after each set; the therapist reads it on the session page."""

from __future__ import annotations

from fastapi import APIRouter

from backend.audit.service import record
from backend.deps import CurrentCaller, DbSession, UserCaller, require_patient_access
from backend.events.hub import Event, publish
from backend.exceptions import AUTH_ERRORS, Forbidden, SessionNotFound, error_responses
from backend.feeling import service
from backend.feeling.schemas import FeelingIn, FeelingOut
from backend.schemas import IdPath
from backend.sessions.models import ExerciseSession
from backend.sessions.service import missing, session_patient
from backend.sessions.triage import PAIN_ALERT_ABOVE
from backend.suggestions.service import suggest_for_feeling
from backend.users.models import User

router = APIRouter(prefix="/api/v1/sessions", tags=["sessions"])


@router.get(
    "/{session_id}/feeling", response_model=FeelingOut, responses=error_responses(*AUTH_ERRORS, SessionNotFound)
)
def get_feeling(session_id: IdPath, caller: CurrentCaller, db_session: DbSession) -> FeelingOut:
    """Returns the pain (0-10) and effort (Borg CR10) the patient gave after the set (nulls: not answered)."""
    patient_id = session_patient(db_session=db_session, session_id=session_id)
    require_patient_access(patient_id, caller=caller, db_session=db_session, hidden_as=missing(session_id))
    return service.get_feeling(db_session=db_session, session_id=session_id)


@router.put(
    "/{session_id}/feeling", response_model=FeelingOut, responses=error_responses(*AUTH_ERRORS, SessionNotFound)
)
def put_feeling(session_id: IdPath, body: FeelingIn, caller: UserCaller, db_session: DbSession) -> FeelingOut:
    """Stores how the set felt: only the patient answers, for their own sets. Pain above the patient's alert level,
    or rising over the week, makes a suggestion for the therapist to review (backend.suggestions.rules)."""
    patient_id = session_patient(db_session=db_session, session_id=session_id)
    require_patient_access(patient_id, caller=caller, db_session=db_session, write=True, hidden_as=missing(session_id))
    if caller.role != "patient":
        raise Forbidden("only the patient says how a set felt")
    out = service.set_feeling(db_session=db_session, session_id=session_id, body=body)
    session = db_session.get(ExerciseSession, session_id)
    patient = db_session.get(User, patient_id)
    if session is not None and patient is not None:
        alert = PAIN_ALERT_ABOVE if patient.pain_alert_above is None else patient.pain_alert_above
        for row in suggest_for_feeling(db_session=db_session, session=session, pain=body.pain, alert_above=alert):
            publish(db_session, Event("suggestion.changed", patient_id, {"suggestion_id": row.id}))
    record(db_session=db_session, caller=caller, action="session.feeling", object_type="session", object_id=session_id,
           patient_id=patient_id, detail={"pain": body.pain, "effort": body.effort})  # fmt: skip
    return out
