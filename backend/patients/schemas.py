"""Patient bodies."""

from __future__ import annotations

import datetime as dt
from typing import Literal

from pydantic import BaseModel, Field

Locale = Literal["en", "de", "es", "fr"]  # backend.i18n.LOCALES


class PatientOut(BaseModel):
    """A patient with the ids of their assigned therapists."""

    id: int = Field(examples=[12])
    email: str = Field(examples=["pat@example.org"])
    full_name: str = Field(examples=["Pat Jones"])
    is_active: bool
    created_at: dt.datetime
    therapist_ids: list[int] = Field(examples=[[3]])
    locale: Locale | None = Field(
        default=None, description="the language of the patient's pages; null: the browser's", examples=["de"]
    )


class PatientUpdate(BaseModel):
    """The patient or their therapist changes the patient's settings."""

    locale: Locale | None = Field(description="the language of the patient's pages; null: the browser's",
                                  examples=["es"])  # fmt: skip
