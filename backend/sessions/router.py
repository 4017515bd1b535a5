"""Sessions: list them, read one's detail, exports and file (the upload, one session with its suggestions, progress
and the dashboard: backend.session_review.router, above the suggestions)."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Depends, Query, Request, Response
from fastapi.responses import JSONResponse

from backend.deps import (
    CurrentCaller,
    DbSession,
    reader_of,
    require_patient_access,
)
from backend.exceptions import (
    AUTH_ERRORS,
    ExerciseNotFound,
    ExportUnavailable,
    InvalidInput,
    InvalidSessionFile,
    PatientNotFound,
    SessionFileRemoved,
    SessionNotFound,
    error_responses,
)
from backend.schemas import DateTimeQuery, IdPath, IdQuery, Page, PageParams, page_params
from backend.sessions import prepared, prepared_export, service
from backend.sessions.deps import SlugQuery
from backend.sessions.encoding import accepts_gzip
from backend.sessions.export import session_export
from backend.sessions.schemas import (
    PreparingOut,
    SessionDetailOut,
    SessionItemOut,
)
from backend.sessions.service import audit, audit_patients, aware, item_fields
from kinect_agent.export.files import ExportFormat as ExportFormatName

router = APIRouter(prefix="/api/v1", tags=["sessions"])
DETAIL_RETRY_AFTER_S = "2"
EXPORT_RETRY_AFTER_S = "5"  # a long recording's export takes a worker tens of seconds


@router.get(
    "/sessions",
    response_model=Page[SessionItemOut],
    responses=error_responses(*AUTH_ERRORS, PatientNotFound, ExerciseNotFound),
)
def list_sessions(
    request: Request,
    caller: CurrentCaller,
    db_session: DbSession,
    page: Annotated[PageParams, Depends(page_params)],
    patient_id: Annotated[IdQuery, Query(description="only this patient's sessions")] = None,
    exercise: SlugQuery = None,
    since: Annotated[DateTimeQuery, Query(description="only sessions started at or after this time")] = None,
) -> Page[SessionItemOut]:
    """Lists the sessions the caller may see, newest first (patients: own; therapists: assigned patients')."""
    if patient_id is not None:
        require_patient_access(patient_id, caller=caller, db_session=db_session)
    exercise_id = service.find_exercise_id(db_session=db_session, slug=exercise) if exercise else None
    visible = service.visible_patients_filter(
        role=caller.role,
        user_id=caller.user.id if caller.user is not None else None,
        device_patient_id=caller.device.patient_id if caller.device is not None else None,
    )
    rows, total = service.list_sessions(
        db_session=db_session,
        visible=visible,
        patient_id=patient_id,
        exercise_id=exercise_id,
        since=aware(since),
        limit=page.limit,
        offset=page.offset,
    )
    audit_patients(db_session, caller, "session.list", sorted({r[0].patient_id for r in rows}))
    t = reader_of(request, caller)
    items = [SessionItemOut(**item_fields(s, slug, reps, rom, ok, t)) for s, slug, reps, rom, ok in rows]
    return Page[SessionItemOut](items=items, total=total, limit=page.limit, offset=page.offset)


@router.get(
    "/sessions/{session_id}/detail",
    response_model=SessionDetailOut,
    responses={
        202: {"model": PreparingOut, "description": "not prepared yet: a worker is building it (Retry-After)"},
        **error_responses(*AUTH_ERRORS, SessionNotFound, InvalidSessionFile, SessionFileRemoved),
    },
)
def read_session_detail(session_id: IdPath, request: Request, caller: CurrentCaller, db_session: DbSession) -> Any:
    """Returns the evidence behind a session's numbers: angle curves, repetitions, workspace, data quality; a
    worker prepares it once (202 with where it is until then). Its texts are in the reader's language."""
    row = service.get_session_row(db_session=db_session, session_id=session_id)
    patient_id = row[0].patient_id
    require_patient_access(patient_id, caller=caller, db_session=db_session, allow_device=False,
                           hidden_as=service.missing(session_id))  # fmt: skip
    body = prepared.read_detail(db_session=db_session, row=row, t=reader_of(request, caller))
    if isinstance(body, prepared.DetailState):
        state = PreparingOut(state=body.state, detail=body.detail)
        return JSONResponse(state.model_dump(), status_code=202, headers={"Retry-After": DETAIL_RETRY_AFTER_S})
    audit(db_session, caller, "session.detail.read", session_id, patient_id)
    return body  # validated against SessionDetailOut, the route's response_model


ExportFormat = Annotated[
    ExportFormatName,  # kinect_agent.export.files.FORMATS: the formats the exporter writes
    Query(description="csv: zip of CSV tables; trc: OpenSim markers (mm); bvh: motion (cm, deg); fhir: R4 Bundle"),
]
_EXPORT_CONTENT = {
    "application/zip": {"schema": {"type": "string", "format": "binary"}},
    "text/plain": {"schema": {"type": "string"}},
    "application/fhir+json": {"schema": {"type": "object"}},
}


@router.get(
    "/sessions/{session_id}/export",
    response_class=Response,
    responses={
        200: {
            "content": _EXPORT_CONTENT,
            "description": "the session as a download: csv → application/zip, trc and bvh → text/plain, "
            "fhir → application/fhir+json",
        },
        202: {
            "model": PreparingOut,
            "description": "a long recording's download is not prepared yet: a worker is building it (Retry-After)",
        },
        **error_responses(
            *AUTH_ERRORS, SessionNotFound, InvalidSessionFile, ExportUnavailable, InvalidInput, SessionFileRemoved
        ),
    },
)
def export_session(
    session_id: IdPath, format: ExportFormat, request: Request, caller: CurrentCaller, db_session: DbSession
) -> Response:
    """Returns the session exported for other software (spreadsheet, OpenSim, animation tools, FHIR servers); a
    recording longer than the server's limits (COACH_EXPORT_DIRECT_MAX_S, _FRAMES) is prepared once by a worker
    (202 with where it is until then)."""
    row = service.get_session_row(db_session=db_session, session_id=session_id)
    session = row[0]
    require_patient_access(session.patient_id, caller=caller, db_session=db_session, allow_device=False,
                           hidden_as=service.missing(session_id))  # fmt: skip
    settings = request.app.state.settings
    small = prepared_export.in_request(duration_s=session.duration_s, n_frames=session.n_frames,
                                       max_s=settings.EXPORT_DIRECT_MAX_S,
                                       max_frames=settings.EXPORT_DIRECT_MAX_FRAMES)  # fmt: skip
    if small:
        result = session_export(db_session=db_session, row=row, fmt=format, max_frames=settings.SESSION_MAX_FRAMES,
                                max_decoded_bytes=settings.SESSION_MAX_DECODED_BYTES)  # fmt: skip
        audit(db_session, caller, "session.export.read", session_id, session.patient_id, {"format": format})
        return _download(result.data, result.media_type, result.file_name, None, stored=False)
    found = prepared_export.read_export(db_session=db_session, row=row, fmt=format, t=reader_of(request, caller))
    if isinstance(found, prepared_export.ExportState):
        state = PreparingOut(state=found.state, detail=found.detail)
        return JSONResponse(state.model_dump(), status_code=202, headers={"Retry-After": EXPORT_RETRY_AFTER_S})
    audit(db_session, caller, "session.export.read", session_id, session.patient_id, {"format": format})
    if accepts_gzip(request.headers.get("accept-encoding")):  # as stored: no request compresses the file again
        return _download(found.gzipped, found.media_type, found.file_name, "gzip")
    return _download(found.data(), found.media_type, found.file_name, None)


def _download(data: bytes, media_type: str, file_name: str, encoding: str | None, *, stored: bool = True) -> Response:
    """Returns a download; a stored one says its encoding (the gzip middleware passes an encoded answer on as it is
    and compresses the others, adding its own Vary)."""
    headers = {"Content-Disposition": f'attachment; filename="{file_name}"'}
    if stored:
        headers["Vary"] = "Accept-Encoding"
    if encoding is not None:
        headers["Content-Encoding"] = encoding
    return Response(content=data, media_type=media_type, headers=headers)


@router.get(
    "/sessions/{session_id}/file",
    response_class=Response,
    responses={
        200: {"content": {"application/octet-stream": {}}, "description": "the stored .khs file"},
        **error_responses(*AUTH_ERRORS, SessionNotFound, SessionFileRemoved),
    },
)
def read_session_file(session_id: IdPath, caller: CurrentCaller, db_session: DbSession) -> Response:
    """Returns the stored session file exactly as it was uploaded."""
    patient_id = service.session_patient(db_session=db_session, session_id=session_id)
    require_patient_access(patient_id, caller=caller, db_session=db_session, hidden_as=service.missing(session_id))
    data = service.session_file(db_session=db_session, session_id=session_id)
    audit(db_session, caller, "session.file.read", session_id, patient_id)
    return Response(
        content=data,
        media_type="application/octet-stream",
        headers={"Content-Disposition": f'attachment; filename="session-{session_id}.khs"'},
    )
