"""Writes and reads audit events."""

from __future__ import annotations

from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

from sqlalchemy import func, select
from sqlalchemy.orm import Session

from backend.audit.models import AuditEvent

if TYPE_CHECKING:
    from backend.deps import Caller


def record(
    *,
    db_session: Session,
    caller: Caller | None,
    action: str,
    object_type: str,
    object_id: object = None,
    patient_id: int | None = None,
    detail: dict[str, Any] | None = None,
) -> AuditEvent:
    """Adds one audit row for the caller (a deps.Caller, or None for anonymous/system) and returns it."""
    event = AuditEvent(
        actor_user_id=caller.user.id if caller is not None and caller.user is not None else None,
        actor_device_id=caller.device.id if caller is not None and caller.device is not None else None,
        action=action,
        object_type=object_type,
        object_id=None if object_id is None else str(object_id),
        patient_id=patient_id,
        ip=caller.ip if caller is not None else None,
        detail=detail,
    )
    db_session.add(event)
    db_session.flush()
    return event


def record_patients(
    *,
    db_session: Session,
    caller: Caller | None,
    action: str,
    object_type: str,
    patient_ids: Iterable[int],
    detail: dict[str, Any] | None = None,
) -> None:
    """Adds one audit row per patient id for the caller, in one flush (a page of patients costs one INSERT)."""
    db_session.add_all(
        AuditEvent(
            actor_user_id=caller.user.id if caller is not None and caller.user is not None else None,
            actor_device_id=caller.device.id if caller is not None and caller.device is not None else None,
            action=action,
            object_type=object_type,
            patient_id=pid,
            ip=caller.ip if caller is not None else None,
            detail=detail,
        )
        for pid in patient_ids
    )
    db_session.flush()


def list_events(
    *,
    db_session: Session,
    limit: int,
    offset: int,
    patient_id: int | None = None,
    actor_user_id: int | None = None,
    action: str | None = None,
) -> tuple[list[AuditEvent], int]:
    """Returns one page of audit events (newest first) and the total number matching the filters."""
    query = select(AuditEvent)
    if patient_id is not None:
        query = query.where(AuditEvent.patient_id == patient_id)
    if actor_user_id is not None:
        query = query.where(AuditEvent.actor_user_id == actor_user_id)
    if action is not None:
        query = query.where(AuditEvent.action == action)
    total = db_session.scalar(select(func.count()).select_from(query.subquery())) or 0
    rows = db_session.scalars(query.order_by(AuditEvent.id.desc()).limit(limit).offset(offset)).all()
    return list(rows), total
