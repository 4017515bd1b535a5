"""The patient's data: download everything (the patient, or an admin for them) and erasure (admins)."""

from __future__ import annotations

import datetime as dt
from collections.abc import Iterator
from typing import Annotated, Literal

from fastapi import APIRouter, Query, Request, Response, status
from fastapi.responses import StreamingResponse
from pydantic import BaseModel, Field

from backend.audit.service import record
from backend.deps import AdminCaller, CurrentCaller, DbSession, require_patient_access
from backend.exceptions import AUTH_ERRORS, Forbidden, InvalidInput, PatientNotFound, error_responses
from backend.records.archive import build_archive
from backend.records.erasure import erase_patient
from backend.records.report import DEFAULT_DAYS, Period, build_report
from backend.schemas import IdPath
from backend.storage import StorageError

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


@router.get(
    "/{patient_id}/archive",
    response_class=StreamingResponse,
    responses={
        200: {
            "content": {"application/zip": {}},
            "description": "a zip of everything held about the patient",
            "headers": {
                "X-Archive-Incomplete-Sessions": {
                    "description": "how many sessions lack their file or an export (named in README.txt)",
                    "schema": {"type": "integer"},
                }
            },
        },
        **error_responses(*AUTH_ERRORS, PatientNotFound, StorageError),
    },
)
def download_archive(
    patient_id: IdPath, request: Request, caller: CurrentCaller, db_session: DbSession
) -> StreamingResponse:
    """Returns everything held about a patient as one zip archive with a README and a manifest (the patient, or an
    admin); each session's file and exports (csv, fhir). A session whose file cannot be read is named in
    the README and the manifest, and counted in the X-Archive-Incomplete-Sessions header; the rest is still given."""
    patient = require_patient_access(patient_id, caller=caller, db_session=db_session)
    user = caller.user
    if user is None or (user.role != "admin" and user.id != patient_id):
        raise Forbidden("only the patient, or an admin on their behalf, downloads all of a patient's data")
    who = "the patient" if user.id == patient_id else f"admin {user.email}"
    record(db_session=db_session, caller=caller, action="patient.archive", object_type="patient",
           object_id=patient_id, patient_id=patient_id)  # fmt: skip
    settings = request.app.state.settings
    built = build_archive(db_session=db_session, patient=patient, requested_by=who, settings=settings)
    archive = built.file
    name = f"patient-{patient_id}-data-{dt.datetime.now(dt.UTC):%Y%m%d}.zip"

    def chunks() -> Iterator[bytes]:
        try:
            while block := archive.read(1 << 20):
                yield block
        finally:
            archive.close()

    return StreamingResponse(chunks(), media_type="application/zip",
                             headers={"Content-Disposition": f'attachment; filename="{name}"',
                                      "X-Archive-Incomplete-Sessions": str(len(built.incomplete))})  # fmt: skip


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
