"""Replies to advice: the patient answers their advice; assigned therapists and admins read the answers."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, Query, Request, status

from backend.audit.service import record, record_patients
from backend.deps import CurrentCaller, DbSession, TherapistOrAdminCaller, UserCaller, require_patient_access
from backend.events.hub import Event, publish
from backend.exceptions import (
    AUTH_ERRORS,
    Forbidden,
    PatientNotFound,
    ReplyNotFound,
    SuggestionNotFound,
    error_responses,
)
from backend.patients.service import visible_patients_query
from backend.replies import service
from backend.replies.schemas import ReadIn, ReadOut, ReplyIn, ReplyOut
from backend.schemas import MAX_ID, IdPath, Page, PageParams, page_params
from backend.users.models import User

router = APIRouter(prefix="/api/v1", tags=["replies"])
CHANGED = "reply.changed"  # the event pages reload on: a reply came, or replies were read
UnreadQuery = Annotated[bool | None, Query(description="true: only unread replies; false: only read ones")]


@router.get(
    "/patients/{patient_id}/replies",
    response_model=Page[ReplyOut],
    responses=error_responses(*AUTH_ERRORS, PatientNotFound),
)
def list_patient_replies(
    patient_id: IdPath,
    request: Request,
    caller: CurrentCaller,
    db_session: DbSession,
    page: Annotated[PageParams, Depends(page_params)],
    unread: UnreadQuery = None,
    suggestion_id: Annotated[int | None, Query(ge=1, le=MAX_ID, description="only replies to this advice")] = None,
) -> Page[ReplyOut]:
    """Lists a patient's replies to their advice, newest first, each with the advice it answers."""
    require_patient_access(patient_id, caller=caller, db_session=db_session)
    items, total = service.list_replies(db_session=db_session, patients=[patient_id], unread=unread,
                                        suggestion_id=suggestion_id, limit=page.limit, offset=page.offset,
                                        accept_language=request.headers.get("accept-language"))  # fmt: skip
    record(db_session=db_session, caller=caller, action="reply.list", object_type="reply", patient_id=patient_id)
    return Page[ReplyOut](items=items, total=total, limit=page.limit, offset=page.offset)


@router.post(
    "/patients/{patient_id}/replies",
    response_model=ReplyOut,
    status_code=status.HTTP_201_CREATED,
    responses=error_responses(*AUTH_ERRORS, PatientNotFound, SuggestionNotFound),
)
def create_reply(
    patient_id: IdPath, body: ReplyIn, request: Request, caller: UserCaller, db_session: DbSession
) -> ReplyOut:
    """Stores the patient's answer to one piece of their advice (only the patient answers); therapists see it at
    once as unread."""
    require_patient_access(patient_id, caller=caller, db_session=db_session, write=True)
    if caller.role != "patient":
        raise Forbidden("only the patient answers their advice")
    out = service.add_reply(db_session=db_session, patient_id=patient_id, body=body,
                            accept_language=request.headers.get("accept-language"))  # fmt: skip
    record(db_session=db_session, caller=caller, action="reply.create", object_type="reply", object_id=out.id,
           patient_id=patient_id, detail={"suggestion_id": out.suggestion_id, "preset": out.preset})  # fmt: skip
    publish(db_session, Event(CHANGED, patient_id, {"reply_id": out.id}))
    return out


@router.post(
    "/patients/{patient_id}/replies/read",
    response_model=ReadOut,
    responses=error_responses(*AUTH_ERRORS, PatientNotFound, ReplyNotFound),
)
def mark_replies_read(
    patient_id: IdPath, body: ReadIn, caller: TherapistOrAdminCaller, db_session: DbSession
) -> ReadOut:
    """Marks replies the therapist has seen as read (an assigned therapist or an admin); answers how many were
    unread."""
    require_patient_access(patient_id, caller=caller, db_session=db_session, write=True)
    marked = service.mark_read(db_session=db_session, patient_id=patient_id, reply_ids=body.reply_ids,
                               reader_id=caller.signed_in_user.id)  # fmt: skip
    record(db_session=db_session, caller=caller, action="reply.read", object_type="reply", patient_id=patient_id,
           detail={"reply_ids": sorted(set(body.reply_ids)), "marked": marked})  # fmt: skip
    if marked:
        publish(db_session, Event(CHANGED, patient_id, {"read": marked}))
    return ReadOut(marked=marked)


@router.get("/replies", response_model=Page[ReplyOut], responses=error_responses(*AUTH_ERRORS))
def list_replies(
    request: Request,
    caller: TherapistOrAdminCaller,
    db_session: DbSession,
    page: Annotated[PageParams, Depends(page_params)],
    unread: UnreadQuery = None,
) -> Page[ReplyOut]:
    """Lists the replies of every patient the caller may see (therapists: assigned; admins: all), newest first."""
    patients = visible_patients_query(caller).with_only_columns(User.id)
    items, total = service.list_replies(db_session=db_session, patients=patients, unread=unread,
                                        limit=page.limit, offset=page.offset,
                                        accept_language=request.headers.get("accept-language"))  # fmt: skip
    record_patients(db_session=db_session, caller=caller, action="reply.list", object_type="reply",
                    patient_ids=sorted({r.patient_id for r in items}))  # fmt: skip
    return Page[ReplyOut](items=items, total=total, limit=page.limit, offset=page.offset)
