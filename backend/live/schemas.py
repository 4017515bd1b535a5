"""Request and response bodies of the live loop."""

from __future__ import annotations

import datetime as dt
import math
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator

SET_ID_PATTERN = r"^[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}$"
EndReason = Literal["target", "stop", "still", "limit", "source", "error"]


class StartIn(BaseModel):
    """Which exercise of the patient's running plan to start."""

    model_config = ConfigDict(extra="forbid")

    plan_item_id: int = Field(ge=1, le=2**31 - 1, description="an item of the patient's current plan")


class StopIn(BaseModel):
    """Which set to stop."""

    model_config = ConfigDict(extra="forbid")

    set_id: str = Field(pattern=SET_ID_PATTERN, description="the set_id that start answered")


class LiveSetOut(BaseModel):
    """A set the home agent was asked to record (or to stop)."""

    set_id: str
    patient_id: int
    device_id: int | None = Field(description="the device asked; None: every device of the patient (stop)")
    exercise_slug: str
    target_reps: int | None
    action: Literal["start", "stop"]


class AgentStatusOut(BaseModel):
    """Whether the patient's home agent is connected now."""

    patient_id: int
    state: Literal["online", "offline", "unpaired"] = Field(
        description="online: connected now; offline: paired but not connected; unpaired: no device"
    )
    device_id: int | None = None
    device_name: str | None = None
    last_seen_at: dt.datetime | None = None


class ProgressIn(BaseModel):
    """One live message of the agent while it records a set (several per second)."""

    model_config = ConfigDict(extra="forbid")

    set_id: str = Field(pattern=SET_ID_PATTERN)
    exercise_slug: str = Field(pattern=r"^[a-z0-9][a-z0-9_]{0,63}$")
    state: Literal["recording", "ended", "failed"]
    count: int = Field(ge=0, le=10_000, description="repetitions so far")
    target: int | None = Field(default=None, ge=1, le=10_000)
    angle_name: str | None = Field(default=None, max_length=64)
    angle_deg: float | None = Field(default=None, ge=-720, le=720, description="the defining angle now, degrees")
    hint: str | None = Field(default=None, max_length=200, description="plain-words advice when tracking is poor")
    elapsed_s: float = Field(default=0.0, ge=0, le=86_400)
    reason: EndReason | None = Field(default=None, description="why the set ended (state ended)")
    session_id: str | None = Field(default=None, pattern=SET_ID_PATTERN, description="the session file's id")
    sent_at: float | None = Field(default=None, description="agent clock, Unix seconds, when the frame was taken")

    @field_validator("angle_deg", "sent_at", "elapsed_s")
    @classmethod
    def _finite(cls, value: float | None) -> float | None:
        if value is not None and not math.isfinite(value):
            raise ValueError("must be a finite number")
        return value
