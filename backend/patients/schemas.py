"""Patient bodies."""

from __future__ import annotations

import datetime as dt

from pydantic import BaseModel, Field


class PatientOut(BaseModel):
    """A patient with the ids of their assigned therapists."""

    id: int = Field(examples=[12])
    email: str = Field(examples=["pat@example.org"])
    full_name: str = Field(examples=["Pat Jones"])
    is_active: bool
    created_at: dt.datetime
    therapist_ids: list[int] = Field(examples=[[3]])
