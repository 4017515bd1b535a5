"""Sessions with the advice made from them: upload (stored with its metrics and suggestions), one session with the
suggestions its reader may see, a patient's progress and summary, the therapist's dashboard."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Depends, Query, Request, Response, status
from sqlalchemy.orm import Session
from starlette.concurrency import run_in_threadpool

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
    InvalidInput,
    InvalidSessionFile,
    MetricsUnreadable,
    PatientIdRequired,
    PatientNotFound,
    SessionConflict,
    SessionNotFound,
    SessionOwnerMismatch,
    SessionTooLarge,
    UploadCutOff,
    error_responses,
)
from backend.exercises.service import get_exercise
from backend.i18n import Translator, therapist_translator
from backend.schemas import DateTimeQuery, IdPath, IdQuery, Page, PageParams, page_params
from backend.session_review import dashboard
from backend.session_review import service as review
from backend.session_review.schemas import SessionOut
from backend.session_texts import reasons
from backend.sessions import prepared, service
from backend.sessions.deps import SlugQuery
from backend.sessions.ingest import check_declared_length, check_owner, decode_upload, read_limited
from backend.sessions.schemas import DashboardRowOut, ProgressOut, ProgressPoint, SummaryOut
from backend.sessions.service import audit, audit_patients, aware, item_fields, stored_metrics
from backend.suggestions import service as suggestions_service

router = APIRouter(prefix="/api/v1", tags=["sessions"])
_UPLOAD_BODY = {
    "requestBody": {
        "required": True,
        "description": "the session file (.khs) bytes",
        "content": {"application/octet-stream": {"schema": {"type": "string", "format": "binary"}}},
    }
}


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
    suggestions = review.session_suggestions(
        db_session=db_session, session_id=session_id, patient_view=_patient_view(caller)
    )
    return SessionOut(
        **item_fields(session, slug, reps, rom, quality, t),
        metrics=None if document is None else reasons.with_texts(stored_metrics(session_id, document), t),
        suggestions=suggestions_service.suggestion_outs(
            suggestions, db_session=db_session, accept_language=accept_language
        ),  # fmt: skip
    )


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
    row, created = review.store_upload(
        db_session=db_session, upload=upload, patient_id=patient_id, exercise=exercise, device_id=device_id
    )
    action = "session.create" if created else "session.upload_repeat"
    audit(db_session, caller, action, row.id, patient_id, {"content_hash": upload.content_hash})
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
    "/sessions/{session_id}",
    response_model=SessionOut,
    responses=error_responses(*AUTH_ERRORS, SessionNotFound, MetricsUnreadable),
)
def read_session(session_id: IdPath, request: Request, caller: CurrentCaller, db_session: DbSession) -> SessionOut:
    """Returns one session with its metrics document and the suggestions the caller may see."""
    row = service.get_session_row(db_session=db_session, session_id=session_id)  # one query, file never loaded
    patient_id = row[0].patient_id
    require_patient_access(patient_id, caller=caller, db_session=db_session, hidden_as=service.missing(session_id))
    audit(db_session, caller, "session.read", session_id, patient_id)
    t = reader_of(request, caller)
    return _session_out(db_session, caller, session_id, t, row, request.headers.get("accept-language"))


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
        db_session=db_session, patient_id=patient.id, exercise_id=exercise_id, since=aware(since),
        t=reader_of(request, caller),
    )  # fmt: skip
    audit(db_session, caller, "session.progress.read", None, patient.id, {"exercise": exercise})
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
    audit(db_session, caller, "session.summary.read", None, patient.id)
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
    audit_patients(db_session, caller, "session.summary.read", [p.id for p in patients], {"via": "dashboard"})
    items = [DashboardRowOut(**summaries[p.id], full_name=p.full_name, email=p.email) for p in patients]
    return Page[DashboardRowOut](items=items, total=total, limit=page.limit, offset=page.offset)
