"""Request and response bodies of a patient's voice setting."""

from __future__ import annotations

import datetime as dt

from pydantic import BaseModel, ConfigDict, Field


class VoiceIn(BaseModel):
    """The patient's voice setting as the patient or their therapist sets it."""

    model_config = ConfigDict(extra="forbid")

    enabled: bool = Field(description="whether the patient's page speaks during a live set", examples=[True])
    volume: float = Field(ge=0.0, le=1.0, description="loudness, 0 (silent) to 1 (full)", examples=[0.8])


class VoiceOut(VoiceIn):
    """A patient's voice setting (the defaults when nobody set it yet)."""

    patient_id: int = Field(examples=[12])
    updated_at: dt.datetime | None = Field(description="null: never set (defaults)")
