"""Sessions: devices and care givers upload .khs files; patients, therapists and admins read sessions and progress."""

from __future__ import annotations

import datetime as dt
from collections.abc import Iterable
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Query, Request, Response, status
from fastapi.responses import JSONResponse
from pydantic import ValidationError
from sqlalchemy.orm import Session
from starlette.concurrency import run_in_threadpool

from backend.analysis import reasons
from backend.audit.service import record, record_patients
from backend.config import Settings
from backend.database import utcnow
from backend.db_slots import lease_of
from backend.deps import (
    Caller,
    CurrentCaller,
    DbSession,
    PatientForRead,
    TherapistOrAdminCaller,
    reader_of,
    require_patient_access,
)
from backend.events.hub import Event, publish
from backend.exceptions import (
    AUTH_ERRORS,
    ExerciseNotFound,
    ExportUnavailable,
    InvalidInput,
    InvalidSessionFile,
    MetricsUnreadable,
    PatientIdRequired,
    PatientNotFound,
    SessionConflict,
    SessionFileRemoved,
    SessionNotFound,
    SessionOwnerMismatch,
    SessionTooLarge,
    UploadCutOff,
    error_responses,
)
from backend.exercises.service import get_exercise
from backend.i18n import ENGLISH, Translator, therapist_translator
from backend.jobs.listing import error_words
from backend.schemas import DateTimeQuery, IdPath, IdQuery, Page, PageParams, page_params
from backend.sessions import dashboard, prepared, prepared_export, service
from backend.sessions.encoding import accepts_gzip
from backend.sessions.export import session_export
from backend.sessions.ingest import check_declared_length, check_owner, decode_upload, read_limited
from backend.sessions.models import ExerciseSession
from backend.sessions.schemas import (
    DashboardRowOut,
    PreparingOut,
    ProgressOut,
    ProgressPoint,
    SessionDetailOut,
    SessionItemOut,
    SessionOut,
    SummaryOut,
)
from backend.suggestions import service as suggestions_service
from kinect_agent.analysis.document import AnalysisDocument, UnreadableDocument, read_document
from kinect_agent.export.files import ExportFormat as ExportFormatName

router = APIRouter(prefix="/api/v1", tags=["sessions"])
DETAIL_RETRY_AFTER_S = "2"
EXPORT_RETRY_AFTER_S = "5"  # a long recording's export takes a worker tens of seconds
SlugQuery = Annotated[
    str | None, Query(min_length=1, max_length=64, description="exercise slug, e.g. 'squat'", examples=["squat"])
]
_UPLOAD_BODY = {
    "requestBody": {
        "required": True,
        "description": "the session file (.khs) bytes",
        "content": {"application/octet-stream": {"schema": {"type": "string", "format": "binary"}}},
    }
}


def _audit(
    db_session: Session,
    caller: Caller,
    action: str,
    session_id: int | None,
    patient_id: int,
    detail: dict[str, Any] | None = None,
) -> None:
    record(
        db_session=db_session,
        caller=caller,
        action=action,
        object_type="exercise_session",
        object_id=session_id,
        patient_id=patient_id,
        detail=detail,
    )


def _audit_patients(
    db_session: Session, caller: Caller, action: str, patient_ids: Iterable[int], detail: dict[str, Any] | None = None
) -> None:
    """Adds what _audit adds once per patient, in one flush."""
    record_patients(
        db_session=db_session,
        caller=caller,
        action=action,
        object_type="exercise_session",
        patient_ids=patient_ids,
        detail=detail,
    )


def _aware(when: dt.datetime | None) -> dt.datetime | None:
    """Returns when with UTC assumed if it carries no time zone."""
    return when.replace(tzinfo=dt.UTC) if when is not None and when.tzinfo is None else when


def _patient_view(caller: Caller) -> bool:
    """Returns whether the caller sees sessions as the patient does (patients and devices: no pending advice)."""
    return caller.role in ("patient", "device")


def _upload_patient(caller: Caller, patient_id: int | None, db_session: Session) -> int:
    """Returns the patient an upload is for after checking the caller may write their data."""
    if patient_id is None:
        if caller.device is not None:
            patient_id = caller.device.patient_id
        elif caller.user is not None and caller.user.role == "patient":
            patient_id = caller.user.id
        else:
            raise PatientIdRequired("a therapist or admin uploads for a patient: name them with ?patient_id=")
    require_patient_access(patient_id, caller=caller, db_session=db_session, write=True, allow_device=True)
    return patient_id


def _session_out(db_session: Session, caller: Caller, session_id: int, t: Translator,
                 row: tuple[Any, ...] | None = None, accept_language: str | None = None) -> SessionOut:  # fmt: skip
    """Returns the session body, its failure and the analysis' reasons in t's language; row: get_session_row's
    answer when the caller already read it; accept_language: the request's, the language of the advice
    (suggestions.service.reader)."""
    row = row or service.get_session_row(db_session=db_session, session_id=session_id)
    session, slug, reps, rom, quality, document = row
    suggestions = service.session_suggestions(
        db_session=db_session, session_id=session_id, patient_view=_patient_view(caller)
    )
    return SessionOut(
        **_item_fields(session, slug, reps, rom, quality, t),
        metrics=None if document is None else reasons.with_texts(_metrics(session_id, document), t),
        suggestions=suggestions_service.suggestion_outs(
            suggestions, db_session=db_session, accept_language=accept_language
        ),  # fmt: skip
    )


def _metrics(session_id: int, document: dict[str, Any]) -> AnalysisDocument:
    """Returns a session's stored metrics document as today's model; raises MetricsUnreadable naming what no
    schema version reads."""
    try:
        return read_document(document)
    except ValidationError as exc:
        first = exc.errors()[0]
        where = ".".join(str(p) for p in first["loc"])
        raise MetricsUnreadable(
            f"the stored metrics document of session {session_id} cannot be read: {where}: {first['msg']}"
        ) from None
    except UnreadableDocument as exc:
        raise MetricsUnreadable(f"the stored metrics document of session {session_id} cannot be read: {exc}") from None


def _item_fields(
    session: ExerciseSession,
    slug: str | None,
    reps: int | None,
    rom: float | None,
    quality: bool | None,
    t: Translator = ENGLISH,
) -> dict[str, Any]:
    """Returns the fields of a session's list item; its failure in t's words (jobs.listing.error_words)."""
    return {
        "id": session.id,
        "client_session_id": session.client_session_id,
        "patient_id": session.patient_id,
        "device_id": session.device_id,
        "exercise_slug": slug,
        "started_at": session.started_at,
        "duration_s": session.duration_s,
        "n_frames": session.n_frames,
        "file_size": session.file_size,
        "content_hash": session.content_hash,
        "status": session.status,
        "error": error_words(session.error, t),
        "repetitions": reps,
        "rom_deg": rom,
        "quality_ok": quality,
        "created_at": session.created_at,
        "file_removed_at": session.file_removed_at,
    }


def _ingest(
    data: bytes,
    *,
    caller: Caller,
    db_session: Session,
    patient_id: int,
    slug: str | None,
    settings: Settings,
    t: Translator,
    accept_language: str | None = None,
) -> tuple[SessionOut, bool]:
    upload = decode_upload(
        data,
        max_frames=settings.SESSION_MAX_FRAMES,
        max_decoded_bytes=settings.SESSION_MAX_DECODED_BYTES,
        max_duration_s=settings.SESSION_MAX_DURATION_S,
    )
    slug = slug or upload.exercise_slug
    if not slug:
        raise InvalidInput("query.exercise: required because the recording's meta.exercise is empty")
    with db_session.no_autoflush:
        exercise = get_exercise(db_session=db_session, slug=slug)
    device_id = caller.device.id if caller.device is not None else None
    check_owner(upload, patient_id=patient_id, device_id=device_id)
    row, created = service.store_upload(
        db_session=db_session, upload=upload, patient_id=patient_id, exercise=exercise, device_id=device_id
    )
    action = "session.create" if created else "session.upload_repeat"
    _audit(db_session, caller, action, row.id, patient_id, {"content_hash": upload.content_hash})
    if created:
        prepared.queue_build(db_session=db_session, session_id=row.id)  # the session page's detail, by a worker
        stored = {"session_id": row.id, "client_session_id": str(upload.client_session_id)}  # the live set's session
        publish(db_session, Event("session.stored", patient_id, stored))
    return _session_out(db_session, caller, row.id, t, accept_language=accept_language), created


@router.post(
    "/sessions",
    response_model=SessionOut,
    status_code=status.HTTP_201_CREATED,
    openapi_extra=_UPLOAD_BODY,
    responses={
        200: {"model": SessionOut, "description": "the same file was stored before; the stored session"},
        **error_responses(
            *AUTH_ERRORS,
            InvalidSessionFile,
            PatientNotFound,
            ExerciseNotFound,
            SessionConflict,
            SessionTooLarge,
            SessionOwnerMismatch,
            PatientIdRequired,
            UploadCutOff,
            InvalidInput,
        ),
    },
)
async def upload_session(
    request: Request,
    response: Response,
    caller: CurrentCaller,
    db_session: DbSession,
    exercise: SlugQuery = None,
    patient_id: Annotated[
        IdQuery,
        Query(
            description="the patient the session is of: required when a therapist or admin uploads (403 "
            "PatientIdRequired); a device or the patient uploads for themselves"
        ),
    ] = None,
) -> SessionOut:
    """Stores an uploaded session file with its metrics and suggestions: 201 when new, 200 when sent before."""
    settings = request.app.state.settings
    limit = settings.MAX_UPLOAD_BYTES
    check_declared_length(request.headers.get("content-length"), limit)
    target = await run_in_threadpool(_upload_patient, caller, patient_id, db_session)
    # The body may take minutes over a patient's uplink: commit the login check (and the device's last_seen_at),
    # which gives the pooled connection back, and the request's database slot with it while the bytes come in.
    await run_in_threadpool(db_session.commit)
    async with lease_of(request).paused():
        data = await read_limited(request.stream(), limit)
    out, created = await run_in_threadpool(
        _ingest,
        data,
        caller=caller,
        db_session=db_session,
        patient_id=target,
        slug=exercise,
        settings=settings,
        t=reader_of(request, caller),
        accept_language=request.headers.get("accept-language"),
    )
    response.status_code = status.HTTP_201_CREATED if created else status.HTTP_200_OK
    return out


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
        since=_aware(since),
        limit=page.limit,
        offset=page.offset,
    )
    _audit_patients(db_session, caller, "session.list", sorted({r[0].patient_id for r in rows}))
    t = reader_of(request, caller)
    items = [SessionItemOut(**_item_fields(s, slug, reps, rom, ok, t)) for s, slug, reps, rom, ok in rows]
    return Page[SessionItemOut](items=items, total=total, limit=page.limit, offset=page.offset)


@router.get(
    "/sessions/{session_id}",
    response_model=SessionOut,
    responses=error_responses(*AUTH_ERRORS, SessionNotFound, MetricsUnreadable),
)
def read_session(session_id: IdPath, request: Request, caller: CurrentCaller, db_session: DbSession) -> SessionOut:
    """Returns one session with its metrics document and the suggestions the caller may see."""
    row = service.get_session_row(db_session=db_session, session_id=session_id)  # one query, file never loaded
    patient_id = row[0].patient_id
    require_patient_access(patient_id, caller=caller, db_session=db_session, hidden_as=service.missing(session_id))
    _audit(db_session, caller, "session.read", session_id, patient_id)
    t = reader_of(request, caller)
    return _session_out(db_session, caller, session_id, t, row, request.headers.get("accept-language"))


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
    _audit(db_session, caller, "session.detail.read", session_id, patient_id)
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
        _audit(db_session, caller, "session.export.read", session_id, session.patient_id, {"format": format})
        return _download(result.data, result.media_type, result.file_name, None, stored=False)
    found = prepared_export.read_export(db_session=db_session, row=row, fmt=format, t=reader_of(request, caller))
    if isinstance(found, prepared_export.ExportState):
        state = PreparingOut(state=found.state, detail=found.detail)
        return JSONResponse(state.model_dump(), status_code=202, headers={"Retry-After": EXPORT_RETRY_AFTER_S})
    _audit(db_session, caller, "session.export.read", session_id, session.patient_id, {"format": format})
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
    _audit(db_session, caller, "session.file.read", session_id, patient_id)
    return Response(
        content=data,
        media_type="application/octet-stream",
        headers={"Content-Disposition": f'attachment; filename="session-{session_id}.khs"'},
    )


@router.get(
    "/patients/{patient_id}/progress",
    response_model=ProgressOut,
    responses=error_responses(*AUTH_ERRORS, PatientNotFound, ExerciseNotFound),
)
def read_progress(
    patient: PatientForRead,
    caller: CurrentCaller,
    db_session: DbSession,
    request: Request,
    exercise: SlugQuery = None,
    since: Annotated[DateTimeQuery, Query(description="only sessions started at or after this time")] = None,
) -> ProgressOut:
    """Returns the patient's sessions as a time series (repetitions, range of motion, indicators), oldest first;
    why balance is missing in the reader's language."""
    exercise_id = service.find_exercise_id(db_session=db_session, slug=exercise) if exercise else None
    points = dashboard.progress(
        db_session=db_session, patient_id=patient.id, exercise_id=exercise_id, since=_aware(since),
        t=reader_of(request, caller),
    )  # fmt: skip
    _audit(db_session, caller, "session.progress.read", None, patient.id, {"exercise": exercise})
    return ProgressOut(patient_id=patient.id, exercise_slug=exercise, points=[ProgressPoint(**p) for p in points])


@router.get(
    "/patients/{patient_id}/summary",
    response_model=SummaryOut,
    responses=error_responses(*AUTH_ERRORS, PatientNotFound),
)
def read_summary(patient: PatientForRead, caller: CurrentCaller, db_session: DbSession, request: Request) -> SummaryOut:
    """Returns the dashboard summary of one patient: last session, this week against the plan, indicators, advice
    (reasons and trends in the language of the therapist pages that Accept-Language asks for)."""
    t = therapist_translator(request.headers.get("accept-language"))
    summary = dashboard.summaries(db_session=db_session, patient_ids=[patient.id], now=utcnow(), t=t)[patient.id]
    _audit(db_session, caller, "session.summary.read", None, patient.id)
    return SummaryOut(**summary)


@router.get(
    "/dashboard",
    response_model=Page[DashboardRowOut],
    responses=error_responses(*AUTH_ERRORS),
)
def read_dashboard(
    caller: TherapistOrAdminCaller,
    db_session: DbSession,
    page: Annotated[PageParams, Depends(page_params)],
    request: Request,
) -> Page[DashboardRowOut]:
    """Returns one page of the caller's patients (therapists: assigned; admins: all), most in need of attention first.

    Rows are sorted by attention score (highest first), then name. Beyond RANKED_PATIENTS_MAX visible patients
    (an admin of a large clinic) the rows come by patient id instead, each still with its score. Reasons and trends
    come in the language of the therapist pages that Accept-Language asks for (English until a catalogue exists).
    """
    now = utcnow()
    t = therapist_translator(request.headers.get("accept-language"))
    patients, total = service.dashboard_patients(
        db_session=db_session, caller=caller, limit=dashboard.RANKED_PATIENTS_MAX + 1, offset=0
    )
    if total <= dashboard.RANKED_PATIENTS_MAX:
        summaries = dashboard.summaries(db_session=db_session, patient_ids=[p.id for p in patients], now=now, t=t)
        patients.sort(key=lambda p: (-summaries[p.id]["attention_score"], (p.full_name or p.email).casefold(), p.id))
        patients = patients[page.offset : page.offset + page.limit]
    else:
        patients, total = service.dashboard_patients(
            db_session=db_session, caller=caller, limit=page.limit, offset=page.offset
        )
        summaries = dashboard.summaries(db_session=db_session, patient_ids=[p.id for p in patients], now=now, t=t)
    _audit_patients(db_session, caller, "session.summary.read", [p.id for p in patients], {"via": "dashboard"})
    items = [DashboardRowOut(**summaries[p.id], full_name=p.full_name, email=p.email) for p in patients]
    return Page[DashboardRowOut](items=items, total=total, limit=page.limit, offset=page.offset)
