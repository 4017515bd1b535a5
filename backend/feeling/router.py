"""How a set felt: the patient answers after each set; the therapist reads it on the session page."""

from __future__ import annotations

from fastapi import APIRouter

from backend.audit.service import record
from backend.deps import CurrentCaller, DbSession, UserCaller, require_patient_access
from backend.exceptions import AUTH_ERRORS, Forbidden, SessionNotFound, error_responses
from backend.feeling import service
from backend.feeling.schemas import FeelingIn, FeelingOut
from backend.schemas import IdPath
from backend.sessions.service import missing, session_patient

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
    """Stores how the set felt: only the patient answers, for their own sets."""
    patient_id = session_patient(db_session=db_session, session_id=session_id)
    require_patient_access(patient_id, caller=caller, db_session=db_session, write=True, hidden_as=missing(session_id))
    if caller.user.role != "patient":
        raise Forbidden("only the patient says how a set felt")
    out = service.set_feeling(db_session=db_session, session_id=session_id, body=body)
    record(db_session=db_session, caller=caller, action="session.feeling", object_type="session", object_id=session_id,
           patient_id=patient_id, detail={"pain": body.pain, "effort": body.effort})  # fmt: skip
    return out
