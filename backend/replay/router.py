"""The 3D replay of a session over the API: its viser scene recording, same access rules as the session itself."""

from __future__ import annotations

from typing import Annotated, Literal

from fastapi import APIRouter, Query, Request, Response

from backend.audit.service import record
from backend.deps import CurrentCaller, DbSession, require_patient_access
from backend.exceptions import AUTH_ERRORS, InvalidSessionFile, SessionFileRemoved, SessionNotFound, error_responses
from backend.replay import service
from backend.schemas import IdPath
from backend.sessions.service import missing, session_patient

router = APIRouter(prefix="/api/v1", tags=["sessions"])
MEDIA_TYPE = "application/octet-stream"


@router.get(
    "/sessions/{session_id}/replay",
    response_class=Response,
    responses={
        200: {"content": {MEDIA_TYPE: {}}, "description": "the session's viser scene recording (.viser)"},
        **error_responses(*AUTH_ERRORS, SessionNotFound, InvalidSessionFile, SessionFileRemoved),
    },
)
def read_replay(
    session_id: IdPath,
    request: Request,
    caller: CurrentCaller,
    db_session: DbSession,
    layer: Annotated[
        Literal["raw", "filtered"] | None, Query(description="one skeleton alone (default: both, raw and filtered)")
    ] = None,
):
    """Returns the 3D replay of a session as a viser scene recording (built on first use, then kept; one skeleton
    alone is built each time)."""
    patient_id = session_patient(db_session=db_session, session_id=session_id)
    require_patient_access(patient_id, caller=caller, db_session=db_session, hidden_as=missing(session_id))
    settings = request.app.state.settings
    data = service.replay_data(db_session=db_session, session_id=session_id, max_frames=settings.SESSION_MAX_FRAMES,
                               max_decoded_bytes=settings.SESSION_MAX_DECODED_BYTES, layer=layer)  # fmt: skip
    record(db_session=db_session, caller=caller, action="session.replay.read", object_type="exercise_session",
           object_id=session_id, patient_id=patient_id)  # fmt: skip
    # identity: the recording is zstd inside already, so the gzip middleware leaves it alone
    headers = {"Cache-Control": "private, no-cache", "Content-Encoding": "identity"}
    return Response(content=data, media_type=MEDIA_TYPE, headers=headers)
