"""The patient's data: download everything (the patient, or an admin for them) and erasure (admins)."""

from __future__ import annotations

import datetime as dt
import logging
from collections.abc import Iterator
from typing import Annotated, Any, Literal

from fastapi import APIRouter, Query, Request, Response, status
from fastapi.responses import JSONResponse, StreamingResponse
from pydantic import BaseModel, Field
from sqlalchemy.orm import Session

from backend.audit.service import record
from backend.deps import AdminCaller, Caller, CurrentCaller, DbSession, reader_of, require_patient_access
from backend.exceptions import AUTH_ERRORS, ArchiveReplaced, Forbidden, InvalidInput, PatientNotFound, error_responses
from backend.records.erasure import erase_patient
from backend.records.prepared_archive import ArchiveState, archive_chunks, archive_state, ask_archive, kept_archive
from backend.records.report import DEFAULT_DAYS, Period, build_report
from backend.schemas import IdPath
from backend.storage import StorageError
from backend.users.models import User

logger = logging.getLogger(__name__)
router = APIRouter(prefix="/api/v1/patients", tags=["patient data"])


class ErasureIn(BaseModel):
    """The admin's confirmation: the patient's e-mail address, typed again."""

    model_config = {"json_schema_extra": {"examples": [{"confirm_email": "rose@demo.clinic"}]}}
    confirm_email: str = Field(description="must equal the patient's e-mail address (case does not matter)")


class ErasureOut(BaseModel):
    """What was erased: rows per table and the number of stored objects deleted."""

    model_config = {"json_schema_extra": {"examples": [{"rows": {"exercise_session": 12, "user": 1}, "objects": 14}]}}
    rows: dict[str, int]
    objects: int


class ArchiveProgress(BaseModel):
    """How far a running build is: sessions written into the zip, and in all."""

    done: int
    total: int


class ArchiveOut(BaseModel):
    """Where a patient's archive is; its URLs are relative to the app's own origin (its configured root path)."""

    model_config = {"json_schema_extra": {"examples": [
        {"state": "preparing", "detail": "A worker is making the archive of all the data.",
         "status_url": "/api/v1/patients/12/archive/status", "download_url": None, "current": False,
         "progress": {"done": 40, "total": 120}, "made_at": None, "sessions": None, "incomplete": None, "size": None},
        {"state": "ready", "detail": "", "status_url": "/api/v1/patients/12/archive/status",
         "download_url": "/api/v1/patients/12/archive?sha256=" + "9f86d081" * 8,
         "current": True, "progress": None, "made_at": "2026-11-27T23:50:00Z", "sessions": 120, "incomplete": 0,
         "size": 48213337},
    ]}}  # fmt: skip
    state: Literal["none", "preparing", "failed", "ready"] = Field(
        description="none: never asked (POST to ask); preparing: queued or being built, ask status_url again in a "
        "few seconds; failed: could not be made (detail says why; POST tries again); ready: download_url gives it"
    )
    detail: str = Field(description="where the build is or why it failed, in the reader's language; empty when ready")
    status_url: str = Field(description="this state, asked again (GET; queues nothing)")
    download_url: str | None = Field(
        description="the kept archive's zip (GET; null when none is kept): pinned by its sha256, it stays valid "
        "until a newer archive replaces it"
    )
    current: bool = Field(description="whether the kept archive covers today's data (false: a newer session, plan, "
                          "advice ... came after it; POST makes a new one)")  # fmt: skip
    progress: ArchiveProgress | None = Field(description="while a worker builds it: sessions written, in all")
    made_at: dt.datetime | None = Field(description="when the kept archive was made (UTC)")
    sessions: int | None = Field(description="the sessions the kept archive holds")
    incomplete: int | None = Field(description="of those, the sessions lacking their file or an export (README.txt)")
    size: int | None = Field(description="bytes of the kept archive's zip")


_READY_STATE: dict[int | str, dict[str, Any]] = {
    200: {"model": ArchiveOut, "description": "the kept archive covers today's data: download_url"}
}
_ASKED_STATE: dict[int | str, dict[str, Any]] = {
    202: {"model": ArchiveOut, "description": "being made by a worker (Retry-After), or failed (detail)"}
}
ARCHIVE_RETRY_AFTER_S = "3"


def _archive_patient(patient_id: int, caller: Caller, db_session: Session) -> tuple[User, str]:
    """Returns the patient whose archive the caller may have and who asks, as the README says it (the patient, or
    an admin on their behalf); raises Forbidden for anyone else."""
    patient = require_patient_access(patient_id, caller=caller, db_session=db_session)
    user = caller.user
    if user is None or (user.role != "admin" and user.id != patient_id):
        raise Forbidden("only the patient, or an admin on their behalf, downloads all of a patient's data")
    return patient, "the patient" if user.id == patient_id else f"admin {user.email}"


def _archive_out(request: Request, patient_id: int, found: ArchiveState) -> ArchiveOut:
    root = f"{request.app.state.settings.root_path}/api/v1/patients/{patient_id}/archive"
    kept = found.kept
    return ArchiveOut(
        state=found.state, detail=found.detail, status_url=f"{root}/status",
        download_url=None if kept is None else f"{root}?sha256={kept.data_hash}", current=found.current,
        progress=None if found.progress is None else ArchiveProgress(done=found.progress[0], total=found.progress[1]),
        made_at=None if kept is None else kept.made_at, sessions=None if kept is None else kept.sessions,
        incomplete=None if kept is None else kept.incomplete, size=None if kept is None else kept.size,
    )  # fmt: skip


def _asked(request: Request, patient_id: int, found: ArchiveState) -> JSONResponse:
    """Returns the 202 of an archive being made or failed, with where its state is (Location, Retry-After)."""
    body = _archive_out(request, patient_id, found)
    return JSONResponse(body.model_dump(mode="json"), status_code=202,
                        headers={"Retry-After": ARCHIVE_RETRY_AFTER_S, "Location": body.status_url})  # fmt: skip


@router.post(
    "/{patient_id}/archive",
    response_model=ArchiveOut,
    responses={**_READY_STATE, **_ASKED_STATE, **error_responses(*AUTH_ERRORS, PatientNotFound)},
)
def ask_for_archive(patient_id: IdPath, request: Request, caller: CurrentCaller, db_session: DbSession) -> Any:
    """Asks for everything held about a patient as one zip archive (the patient, or an admin): a worker makes it
    once (202 with where it is: ask status_url until ready), however often it is asked; 200 when the kept
    archive covers today's data. A failed build is said (state failed) and asking again tries it again."""
    patient, who = _archive_patient(patient_id, caller, db_session)
    found = ask_archive(db_session=db_session, patient=patient, requested_by=who, t=reader_of(request, caller))
    if found.state != "ready":
        record(db_session=db_session, caller=caller, action="patient.archive.ask", object_type="patient",
               object_id=patient_id, patient_id=patient_id)  # fmt: skip
        return _asked(request, patient_id, found)
    return _archive_out(request, patient_id, found)


@router.get(
    "/{patient_id}/archive/status",
    response_model=ArchiveOut,
    responses=error_responses(*AUTH_ERRORS, PatientNotFound),
)
def archive_status(patient_id: IdPath, request: Request, caller: CurrentCaller, db_session: DbSession) -> ArchiveOut:
    """Returns where a patient's archive is (none, preparing with its progress, failed with why, ready with its
    download URL and whether it covers today's data); queues nothing."""
    patient, _ = _archive_patient(patient_id, caller, db_session)
    found = archive_state(db_session=db_session, patient=patient, t=reader_of(request, caller))
    return _archive_out(request, patient_id, found)


@router.get(
    "/{patient_id}/archive",
    response_class=Response,
    responses={
        200: {
            "content": {"application/zip": {"schema": {"type": "string", "format": "binary"}}},
            "description": "a zip of everything held about the patient, made by a worker and kept in the object store",
            "headers": {
                "X-Archive-Incomplete-Sessions": {
                    "description": "how many sessions lack their file or an export (named in README.txt)",
                    "schema": {"type": "integer"},
                },
                "X-Archive-Made-At": {"description": "when it was made (UTC, ISO 8601)", "schema": {"type": "string"}},
                "X-Archive-SHA256": {
                    "description": "the zip's sha256 (64 hex digits), checked by the server as it reads the zip; "
                    "on S3 a mismatch found mid-transfer aborts the connection short of Content-Length",
                    "schema": {"type": "string"},
                },
            },
        },
        **_ASKED_STATE,
        **error_responses(*AUTH_ERRORS, PatientNotFound, ArchiveReplaced, StorageError),
    },
)
def download_archive(
    patient_id: IdPath,
    request: Request,
    caller: CurrentCaller,
    db_session: DbSession,
    sha256: Annotated[
        str | None,
        Query(
            pattern="^[0-9a-f]{64}$",
            description="the kept archive's sha256, as status_url's download_url gives it: "
            "that archive, even when newer data came since; without it, the archive of today's data",
        ),
    ] = None,
) -> Response:
    """Returns everything held about a patient as one zip archive with a README and a manifest (the patient, or an
    admin), as a worker made it; each session's file and exports (csv, fhir). A session whose file cannot be read
    is named in the README and the manifest, and counted in the X-Archive-Incomplete-Sessions header. Never built
    in the request: without a kept archive of today's data this asks for one (202, as POST does). Streamed from the
    object store a chunk at a time with its sha256 checked: on the filesystem before the first byte (a corrupt zip
    answers 500 StoredObjectCorrupt), on S3 on the way (a mismatch aborts the connection before Content-Length)."""
    patient, who = _archive_patient(patient_id, caller, db_session)
    if sha256 is not None:
        kept = kept_archive(db_session=db_session, patient_id=patient_id)
        if kept is None or kept.data_hash != sha256:
            raise ArchiveReplaced("this archive was replaced by a newer one or erased: ask for the archive again")
    else:
        found = ask_archive(db_session=db_session, patient=patient, requested_by=who, t=reader_of(request, caller))
        if found.state != "ready" or found.kept is None:
            return _asked(request, patient_id, found)
        kept = found.kept
    chunks = archive_chunks(kept)  # before the audit row: a missing (or, local, corrupt) zip answers its error
    record(db_session=db_session, caller=caller, action="patient.archive", object_type="patient",
           object_id=patient_id, patient_id=patient_id, detail={"sha256": kept.data_hash})  # fmt: skip
    return StreamingResponse(_aborting(chunks, patient_id), media_type="application/zip",
                             headers={"Content-Disposition": f'attachment; filename="{kept.file_name}"',
                                      "Content-Length": str(kept.size), "X-Archive-SHA256": kept.data_hash,
                                      "X-Archive-Incomplete-Sessions": str(kept.incomplete),
                                      "X-Archive-Made-At": kept.made_at.isoformat()})  # fmt: skip


def _aborting(chunks: Iterator[bytes], patient_id: int) -> Iterator[bytes]:
    """Yields the archive's chunks; a store error found after the headers went out (S3: the sha256 is known only at
    the end) is logged and raised on, so the server drops the connection short of Content-Length."""
    try:
        yield from chunks
    except StorageError as exc:
        logger.error("archive download of patient %s aborted mid-transfer: %s", patient_id, exc.message)
        raise


@router.post(
    "/{patient_id}/erasure",
    response_model=ErasureOut,
    status_code=status.HTTP_200_OK,
    responses=error_responses(*AUTH_ERRORS, PatientNotFound, InvalidInput),
)
def erase(patient_id: IdPath, body: ErasureIn, caller: AdminCaller, db_session: DbSession) -> ErasureOut:
    """Erases a patient: every row and stored object goes; the audit log keeps that an erasure happened, by whom,
    when (admins; the body repeats the patient's e-mail address as a confirmation)."""
    patient = require_patient_access(patient_id, caller=caller, db_session=db_session)
    if body.confirm_email.strip().lower() != patient.email.lower():
        raise InvalidInput(f"confirm_email does not match the e-mail address of patient {patient_id}; nothing erased")
    result = erase_patient(db_session=db_session, patient=patient, caller=caller)
    return ErasureOut(rows=result.rows, objects=len(result.objects))


@router.get(
    "/{patient_id}/report.pdf",
    response_class=Response,
    responses={
        200: {"content": {"application/pdf": {}}, "description": "the progress report, black-and-white safe"},
        **error_responses(*AUTH_ERRORS, PatientNotFound, InvalidInput),
    },
)
def progress_report(
    patient_id: IdPath,
    caller: CurrentCaller,
    db_session: DbSession,
    start: Annotated[
        dt.date | None,
        Query(alias="from", description=f"first day (default: the {DEFAULT_DAYS} days up to `to`, both included)"),
    ] = None,
    end: Annotated[dt.date | None, Query(alias="to", description="last day (default: today, UTC)")] = None,
    paper: Literal["a4", "letter"] = "a4",
) -> Response:
    """Returns the progress report of a patient over a period as a PDF (the patient, their therapists, admins)."""
    patient = require_patient_access(patient_id, caller=caller, db_session=db_session)
    if caller.device is not None:
        raise Forbidden("devices do not read reports")
    period = Period.asked(start, end)
    who = caller.signed_in_user.full_name or caller.signed_in_user.email
    record(db_session=db_session, caller=caller, action="patient.report", object_type="patient", object_id=patient_id,
           patient_id=patient_id, detail={"from": str(period.start), "to": str(period.end)})  # fmt: skip
    pdf = build_report(db_session=db_session, patient=patient, period=period, made_by=who, paper=paper)
    name = f"progress-patient-{patient_id}-{period.start}-{period.end}.pdf"
    return Response(pdf, media_type="application/pdf", headers={"Content-Disposition": f'inline; filename="{name}"'})
