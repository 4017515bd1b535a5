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

    plan_item_id: int = Field(ge=1, le=2**31 - 1, description="an item of the patient's current plan", examples=[41])


class StopIn(BaseModel):
    """Which set to stop."""

    model_config = ConfigDict(extra="forbid")

    set_id: str = Field(
        pattern=SET_ID_PATTERN,
        description="the set_id that start answered",
        examples=["3f2b8c1e-4d5a-4e6f-8a9b-0c1d2e3f4a5b"],
    )


class LiveSetOut(BaseModel):
    """A set the home agent was asked to record (or to stop)."""

    set_id: str = Field(examples=["3f2b8c1e-4d5a-4e6f-8a9b-0c1d2e3f4a5b"])
    patient_id: int = Field(examples=[12])
    device_id: int | None = Field(description="the device asked; None: every device of the patient (stop)",
                                  examples=[7])  # fmt: skip
    exercise_slug: str = Field(examples=["elbow_flexion"])
    target_reps: int | None = Field(examples=[10])
    action: Literal["start", "stop"]


class AgentStatusOut(BaseModel):
    """Whether the patient's home agent is connected now."""

    patient_id: int = Field(examples=[12])
    state: Literal["online", "offline", "unpaired"] = Field(
        description="online: connected now; offline: paired but not connected; unpaired: no device",
        examples=["online"],
    )
    device_id: int | None = None
    device_name: str | None = None
    last_seen_at: dt.datetime | None = None


class ProgressIn(BaseModel):
    """One live message of the agent while it records a set (several per second)."""

    model_config = ConfigDict(extra="forbid")

    set_id: str = Field(pattern=SET_ID_PATTERN, examples=["3f2b8c1e-4d5a-4e6f-8a9b-0c1d2e3f4a5b"])
    exercise_slug: str = Field(pattern=r"^[a-z0-9][a-z0-9_]{0,63}$", examples=["elbow_flexion"])
    state: Literal["starting", "recording", "ended", "failed"] = Field(
        description="starting: the Start was heard and the set is being readied (no count yet); recording: counting"
    )
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
