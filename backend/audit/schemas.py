"""Audit bodies."""

from __future__ import annotations

import datetime as dt
from typing import Any

from pydantic import BaseModel, ConfigDict


class AuditEventOut(BaseModel):
    """One audit event."""

    model_config = ConfigDict(from_attributes=True)
    id: int
    at: dt.datetime
    actor_user_id: int | None
    actor_device_id: int | None
    action: str
    object_type: str
    object_id: str | None
    patient_id: int | None
    ip: str | None
    detail: dict[str, Any] | None
