"""The 3D replay of a session over the API: its viser scene recording, same access rules as the session itself.

Every recording (both skeletons, or one alone with ?layer=) is built by a worker (backend/replay/jobs.py): until it
is stored, the replay answers 202 with where its build is, and `/replay/state` says the same without the
recording's bytes (the page polls it, then opens the viewer).
"""

from __future__ import annotations

from typing import Annotated, Literal

from fastapi import APIRouter, Query, Request, Response
from fastapi.responses import JSONResponse
from pydantic import BaseModel, Field
from sqlalchemy.orm import Session

from backend.audit.service import record
from backend.deps import Caller, CurrentCaller, DbSession, reader_of, require_patient_access
from backend.exceptions import (
    AUTH_ERRORS,
    InvalidSessionFile,
    SessionFileRemoved,
    SessionNotFound,
    error_responses,
)
from backend.replay import jobs, service
from backend.replay.models import BOTH
from backend.schemas import IdPath
from backend.sessions.service import missing, session_patient

router = APIRouter(prefix="/api/v1", tags=["sessions"])
MEDIA_TYPE = "application/octet-stream"
RETRY_AFTER_S = "2"
LayerQuery = Annotated[
    Literal["raw", "filtered"] | None, Query(description="one skeleton alone (default: both, raw and filtered)")
]


class ReplayStateOut(BaseModel):
    """Where a session's replay is: ready to play, being prepared by a worker, or failed (why, in words)."""

    model_config = {"json_schema_extra": {"examples": [{"state": "preparing",
                    "detail": "The replay is queued; a worker will build it in a moment."}]}}  # fmt: skip
    state: Literal["ready", "preparing", "failed"] = Field(description="preparing: ask again in a few seconds")
    detail: str


def _visible(session_id: int, caller: Caller, db_session: Session) -> int:
    patient_id = session_patient(db_session=db_session, session_id=session_id)
    require_patient_access(patient_id, caller=caller, db_session=db_session, hidden_as=missing(session_id))
    return patient_id


@router.get(
    "/sessions/{session_id}/replay/state",
    response_model=ReplayStateOut,
    responses=error_responses(*AUTH_ERRORS, SessionNotFound, SessionFileRemoved),
)
def read_replay_state(
    session_id: IdPath, request: Request, caller: CurrentCaller, db_session: DbSession, layer: LayerQuery = None
) -> ReplayStateOut:
    """Returns whether the session's replay is ready, queueing its build by a worker when it is not (once, however
    many ask at the same time; again after a failure, a few times), in the reader's language."""
    _visible(session_id, caller, db_session)
    found = jobs.request_replay(db_session=db_session, session_id=session_id, layers=layer or BOTH,
                                t=reader_of(request, caller))  # fmt: skip
    return ReplayStateOut(state=found.state, detail=found.detail)


@router.get(
    "/sessions/{session_id}/replay",
    response_class=Response,
    responses={
        200: {"content": {MEDIA_TYPE: {}}, "description": "the session's viser scene recording (.viser)"},
        202: {"model": ReplayStateOut, "description": "not built yet: a worker is preparing it (Retry-After)"},
        **error_responses(*AUTH_ERRORS, SessionNotFound, InvalidSessionFile, SessionFileRemoved),
    },
)
def read_replay(
    session_id: IdPath,
    request: Request,
    caller: CurrentCaller,
    db_session: DbSession,
    layer: LayerQuery = None,
) -> Response:
    """Returns the 3D replay of a session (both skeletons, or one alone) as a viser scene recording once a worker
    has built it (202 with its state until then)."""
    patient_id = _visible(session_id, caller, db_session)
    data = service.stored_replay(db_session=db_session, session_id=session_id, layers=layer or BOTH)
    if data is None:
        found = jobs.request_replay(db_session=db_session, session_id=session_id, layers=layer or BOTH,
                                    t=reader_of(request, caller))  # fmt: skip
        body = ReplayStateOut(state=found.state, detail=found.detail)
        return JSONResponse(body.model_dump(), status_code=202, headers={"Retry-After": RETRY_AFTER_S})
    record(db_session=db_session, caller=caller, action="session.replay.read", object_type="exercise_session",
           object_id=session_id, patient_id=patient_id)  # fmt: skip
    # identity: the recording is zstd inside already, so the gzip middleware leaves it alone
    headers = {"Cache-Control": "private, no-cache", "Content-Encoding": "identity"}
    return Response(content=data, media_type=MEDIA_TYPE, headers=headers)
