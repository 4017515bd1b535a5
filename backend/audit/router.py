"""The audit log (admins read it)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, Query

from backend.audit import service
from backend.audit.schemas import AuditEventOut
from backend.deps import AdminCaller, DbSession
from backend.exceptions import Forbidden, InsufficientScope, NotAuthenticated, error_responses
from backend.schemas import IdQuery, Page, PageParams, page_params

router = APIRouter(prefix="/api/v1/audit", tags=["audit"])


@router.get(
    "", response_model=Page[AuditEventOut], responses=error_responses(NotAuthenticated, Forbidden, InsufficientScope)
)
def list_events(
    caller: AdminCaller,
    db_session: DbSession,
    page: Annotated[PageParams, Depends(page_params)],
    patient_id: IdQuery = None,
    actor_user_id: IdQuery = None,
    action: Annotated[str | None, Query(max_length=64, examples=["plan.read"])] = None,
) -> Page[AuditEventOut]:
    """Lists audit events, newest first, optionally for one patient, actor or action (admin only)."""
    rows, total = service.list_events(
        db_session=db_session,
        limit=page.limit,
        offset=page.offset,
        patient_id=patient_id,
        actor_user_id=actor_user_id,
        action=action,
    )
    return Page[AuditEventOut](
        items=[AuditEventOut.model_validate(e) for e in rows], total=total, limit=page.limit, offset=page.offset
    )
