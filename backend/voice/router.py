"""A patient's voice setting: whether their page speaks during a live set, and how loud."""

from __future__ import annotations

from fastapi import APIRouter

from backend.audit.service import record
from backend.deps import CurrentCaller, DbSession, UserCaller, require_patient_access
from backend.exceptions import AUTH_ERRORS, PatientNotFound, error_responses
from backend.schemas import IdPath
from backend.voice import service
from backend.voice.schemas import VoiceIn, VoiceOut

router = APIRouter(prefix="/api/v1/patients", tags=["voice"])


@router.get("/{patient_id}/voice", response_model=VoiceOut, responses=error_responses(*AUTH_ERRORS, PatientNotFound))
def get_voice(patient_id: IdPath, caller: CurrentCaller, db_session: DbSession) -> VoiceOut:
    """Returns whether the patient's page speaks during a live set, and how loud (defaults: on, full volume)."""
    require_patient_access(patient_id, caller=caller, db_session=db_session)
    return service.get_voice(db_session=db_session, patient_id=patient_id)


@router.put("/{patient_id}/voice", response_model=VoiceOut, responses=error_responses(*AUTH_ERRORS, PatientNotFound))
def put_voice(patient_id: IdPath, body: VoiceIn, caller: UserCaller, db_session: DbSession) -> VoiceOut:
    """Sets the patient's voice: the patient from their page, or their therapist (an admin)."""
    require_patient_access(patient_id, caller=caller, db_session=db_session, write=True)
    out = service.set_voice(
        db_session=db_session, patient_id=patient_id, body=body, by_user_id=caller.signed_in_user.id
    )
    record(db_session=db_session, caller=caller, action="voice.update", object_type="patient", object_id=patient_id,
           patient_id=patient_id, detail={"enabled": body.enabled, "volume": body.volume})  # fmt: skip
    return out
