"""Camera sets' routes: the patient's consent, start, landmark batches and end (patients only, their own sets)."""

from __future__ import annotations

import uuid
from typing import Annotated

from fastapi import APIRouter, Path, Request, Response, status

from backend.audit.service import record
from backend.camera import finish, live_count, service
from backend.camera.errors import (
    BatchConflict,
    BatchOutOfOrder,
    CameraRateLimited,
    CameraSetEnded,
    CameraSetNotFound,
    ConsentMissing,
)
from backend.camera.schemas import BatchIn, BatchOut, CameraSetOut, CameraStartIn, ConsentIn, ConsentOut, EndIn
from backend.deps import Caller, DbSession, UserCaller
from backend.exceptions import AUTH_ERRORS, Forbidden, InvalidInput, PlanNotFound, error_responses

router = APIRouter(prefix="/api/v1/camera", tags=["camera"])
SetId = Annotated[uuid.UUID, Path(description="the set_id that start answered")]


def _the_patient(caller: Caller) -> int:
    if caller.user is None or caller.user.role != "patient":
        raise Forbidden("only patients record camera sets, their own, from their page")
    return caller.user.id


@router.get("/consent", response_model=ConsentOut, responses=error_responses(*AUTH_ERRORS))
def read_consent(caller: UserCaller, db_session: DbSession) -> ConsentOut:
    """Returns whether the calling patient agreed to the current consent text of camera sets."""
    return service.consent_status(db_session=db_session, patient_id=_the_patient(caller))


@router.post("/consent", response_model=ConsentOut, responses=error_responses(*AUTH_ERRORS, InvalidInput))
def give_consent(body: ConsentIn, caller: UserCaller, db_session: DbSession) -> ConsentOut:
    """Records that the calling patient agreed to the consent text body.consent_version (the current one)."""
    pid = _the_patient(caller)
    out = service.give_consent(db_session=db_session, patient_id=pid, consent_version=body.consent_version)
    record(
        db_session=db_session,
        caller=caller,
        action="camera.consent",
        object_type="camera_consent",
        object_id=pid,
        patient_id=pid,
        detail={"consent_version": body.consent_version},
    )
    return out


@router.delete("/consent", response_model=ConsentOut, responses=error_responses(*AUTH_ERRORS))
def withdraw_consent(caller: UserCaller, db_session: DbSession) -> ConsentOut:
    """Withdraws the calling patient's consent: no camera set starts until they agree again."""
    pid = _the_patient(caller)
    out = service.withdraw_consent(db_session=db_session, patient_id=pid)
    record(
        db_session=db_session,
        caller=caller,
        action="camera.consent_withdrawn",
        object_type="camera_consent",
        object_id=pid,
        patient_id=pid,
    )
    return out


@router.post(
    "/sets",
    response_model=CameraSetOut,
    status_code=status.HTTP_201_CREATED,
    responses=error_responses(*AUTH_ERRORS, PlanNotFound, ConsentMissing, CameraRateLimited),
)
def start_set(body: CameraStartIn, caller: UserCaller, db_session: DbSession) -> CameraSetOut:
    """Starts a set of an exercise of the calling patient's plan, recorded with their own camera."""
    pid = _the_patient(caller)
    row = service.start_set(db_session=db_session, patient_id=pid, plan_item_id=body.plan_item_id, model=body.model)
    out = service.set_out(db_session, row)
    record(
        db_session=db_session,
        caller=caller,
        action="camera.start",
        object_type="camera_set",
        object_id=out.set_id,
        patient_id=pid,
        detail={"exercise": out.exercise_slug, "model": body.model},
    )
    return out


@router.get("/sets/{set_id}", response_model=CameraSetOut, responses=error_responses(*AUTH_ERRORS, CameraSetNotFound))
def read_set(set_id: SetId, caller: UserCaller, db_session: DbSession) -> CameraSetOut:
    """Returns one of the calling patient's camera sets (where it stands: the last batch received, the session)."""
    return service.set_out(
        db_session, service.get_set(db_session=db_session, patient_id=_the_patient(caller), set_id=set_id)
    )


@router.post(
    "/sets/{set_id}/batches",
    response_model=BatchOut,
    status_code=status.HTTP_201_CREATED,
    responses={
        200: {"model": BatchOut, "description": "this batch was received before; nothing new stored"},
        **error_responses(
            *AUTH_ERRORS,
            CameraSetNotFound,
            CameraSetEnded,
            BatchOutOfOrder,
            BatchConflict,
            InvalidInput,
            CameraRateLimited,
        ),
    },
)
def post_batch(set_id: SetId, body: BatchIn, response: Response, caller: UserCaller, db_session: DbSession) -> BatchOut:
    """Stores a batch of landmarks of the calling patient's set and answers the live count (201; 200: repeated)."""
    row = service.get_set(db_session=db_session, patient_id=_the_patient(caller), set_id=set_id, for_update=True)
    batch, repeated = service.add_batch(db_session=db_session, row=row, body=body)
    out = live_count.advance(
        db_session=db_session, row=row, seq=body.seq, batch=None if repeated else batch, fps=body.fps
    )
    response.status_code = status.HTTP_200_OK if repeated else status.HTTP_201_CREATED
    return out.model_copy(update={"repeated": repeated, "seq": body.seq})


@router.post(
    "/sets/{set_id}/end",
    response_model=CameraSetOut,
    responses=error_responses(*AUTH_ERRORS, CameraSetNotFound, BatchOutOfOrder),
)
def end_set(set_id: SetId, body: EndIn, request: Request, caller: UserCaller, db_session: DbSession) -> CameraSetOut:
    """Ends the calling patient's set: the offline pipeline runs and the session is stored once (a repeated end
    answers the same stored session). status failed with error: too few frames to analyse, nothing stored."""
    pid = _the_patient(caller)
    row = service.get_set(db_session=db_session, patient_id=pid, set_id=set_id, for_update=True)
    was = row.status
    settings = request.app.state.settings
    row = finish.end_set(
        db_session=db_session,
        row=row,
        last_seq=body.last_seq,
        reason=body.reason,
        max_frames=settings.SESSION_MAX_FRAMES,
        max_decoded_bytes=settings.SESSION_MAX_DECODED_BYTES,
    )
    if was == "recording":
        record(
            db_session=db_session,
            caller=caller,
            action="camera.end",
            object_type="camera_set",
            object_id=str(row.id),
            patient_id=pid,
            detail={"status": row.status, "session_id": row.session_id, "reason": body.reason},
        )
    return service.set_out(db_session, row)
