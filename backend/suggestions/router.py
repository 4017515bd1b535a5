"""Suggestions: patients read approved advice; assigned therapists and admins review rule output and write their own."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Query, Request, status
from sqlalchemy import select
from sqlalchemy.orm import Session

from backend.audit.service import record
from backend.deps import Caller, CurrentCaller, DbSession, TherapistOrAdminCaller, require_patient_access
from backend.events.hub import Event, publish
from backend.exceptions import (
    AUTH_ERRORS,
    InvalidInput,
    PatientNotFound,
    SuggestionNotFound,
    SuggestionNotPending,
    error_responses,
)
from backend.schemas import MAX_ID, IdPath, Page, PageParams, page_params
from backend.sessions.models import ExerciseSession
from backend.suggestions import service
from backend.suggestions.models import Suggestion
from backend.suggestions.schemas import Status, SuggestionIn, SuggestionOut

router = APIRouter(prefix="/api/v1", tags=["suggestions"])


def _audit(
    db_session: Session,
    caller: Caller,
    action: str,
    suggestion_id: int | None,
    patient_id: int,
    detail: dict[str, Any] | None = None,
) -> None:
    record(
        db_session=db_session,
        caller=caller,
        action=action,
        object_type="suggestion",
        object_id=suggestion_id,
        patient_id=patient_id,
        detail=detail,
    )


def _outs(db_session: Session, rows: Sequence[Suggestion], request: Request) -> list[SuggestionOut]:
    """Returns suggestions as the API shows them (service.suggestion_outs), in the request's language."""
    return service.suggestion_outs(rows, db_session=db_session,
                                   accept_language=request.headers.get("accept-language"))  # fmt: skip


def _sees_everything(caller: Caller) -> bool:
    return caller.user is not None and caller.user.role in ("therapist", "admin")


@router.get(
    "/patients/{patient_id}/suggestions",
    response_model=Page[SuggestionOut],
    responses=error_responses(*AUTH_ERRORS, PatientNotFound),
)
def list_suggestions(
    patient_id: IdPath,
    request: Request,
    caller: CurrentCaller,
    db_session: DbSession,
    page: Annotated[PageParams, Depends(page_params)],
    status_filter: Annotated[
        Status | None, Query(alias="status", description="only this status (patients only ever see 'approved')")
    ] = None,
    session_id: Annotated[int | None, Query(ge=1, le=MAX_ID, description="only suggestions about this session")] = None,
    decided: Annotated[
        bool | None, Query(description="true: only decided ones (approved, dismissed, superseded, therapists' own)")
    ] = None,
) -> Page[SuggestionOut]:
    """Lists a patient's suggestions, newest first: patients and devices see approved ones, therapists all."""
    require_patient_access(patient_id, caller=caller, db_session=db_session)
    rows, total = service.list_suggestions(
        db_session=db_session,
        patient_id=patient_id,
        patient_view=not _sees_everything(caller),
        status=status_filter,
        session_id=session_id,
        decided=decided,
        limit=page.limit,
        offset=page.offset,
    )
    _audit(db_session, caller, "suggestion.list", None, patient_id)
    items = _outs(db_session, rows, request)
    return Page[SuggestionOut](items=items, total=total, limit=page.limit, offset=page.offset)


@router.post(
    "/patients/{patient_id}/suggestions",
    response_model=SuggestionOut,
    status_code=status.HTTP_201_CREATED,
    responses=error_responses(*AUTH_ERRORS, PatientNotFound, InvalidInput),
)
def create_suggestion(
    patient_id: IdPath, body: SuggestionIn, request: Request, caller: TherapistOrAdminCaller, db_session: DbSession
) -> SuggestionOut:
    """Writes a suggestion to a patient (an assigned therapist or an admin); the patient sees it at once."""
    require_patient_access(patient_id, caller=caller, db_session=db_session, write=True)
    if body.session_id is not None:
        owner = db_session.scalar(select(ExerciseSession.patient_id).where(ExerciseSession.id == body.session_id))
        if owner != patient_id:
            raise InvalidInput(f"body.session_id: session {body.session_id} is not a session of patient {patient_id}")
    row = service.add_therapist_suggestion(
        db_session=db_session,
        patient_id=patient_id,
        author_id=caller.signed_in_user.id,
        text=body.text,
        session_id=body.session_id,
    )
    _audit(db_session, caller, "suggestion.create", row.id, patient_id)
    publish(db_session, Event("suggestion.changed", patient_id, {"suggestion_id": row.id}))
    return _outs(db_session, [row], request)[0]


def _decide(
    suggestion_id: int, new_status: str, caller: Caller, db_session: Session, request: Request
) -> SuggestionOut:
    row = service.get_suggestion(db_session=db_session, suggestion_id=suggestion_id)
    require_patient_access(row.patient_id, caller=caller, db_session=db_session, write=True,
                           hidden_as=service.missing(suggestion_id))  # fmt: skip
    service.decide(
        db_session=db_session,
        suggestion=row,
        status=new_status,
        decided_by_id=caller.signed_in_user.id,
    )
    action = "suggestion.approve" if new_status == "approved" else "suggestion.dismiss"
    _audit(db_session, caller, action, row.id, row.patient_id, {"rule": row.rule})
    publish(db_session, Event("suggestion.changed", row.patient_id, {"suggestion_id": row.id}))
    return _outs(db_session, [row], request)[0]


DECIDE_ERRORS = error_responses(*AUTH_ERRORS, SuggestionNotFound, SuggestionNotPending)


@router.post("/suggestions/{suggestion_id}/approve", response_model=SuggestionOut, responses=DECIDE_ERRORS)
def approve_suggestion(
    suggestion_id: IdPath, request: Request, caller: TherapistOrAdminCaller, db_session: DbSession
) -> SuggestionOut:
    """Approves a pending system suggestion so the patient sees it (an assigned therapist or an admin)."""
    return _decide(suggestion_id, "approved", caller, db_session, request)


@router.post("/suggestions/{suggestion_id}/dismiss", response_model=SuggestionOut, responses=DECIDE_ERRORS)
def dismiss_suggestion(
    suggestion_id: IdPath, request: Request, caller: TherapistOrAdminCaller, db_session: DbSession
) -> SuggestionOut:
    """Dismisses a pending system suggestion; the patient never sees it (an assigned therapist or an admin)."""
    return _decide(suggestion_id, "dismissed", caller, db_session, request)
