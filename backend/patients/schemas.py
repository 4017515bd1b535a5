"""Patient bodies."""

from __future__ import annotations

import datetime as dt
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field

from backend.sessions.triage import PAIN_ALERT_ABOVE

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
    pain_alert_above: int = Field(
        default=PAIN_ALERT_ABOVE,
        description="pain said after a set (0-10) above this raises the patient's attention score "
        f"(set by the therapist; {PAIN_ALERT_ABOVE} unless set)",
        examples=[5],
    )


class PatientUpdate(BaseModel):
    """The patient or their therapist changes the patient's settings; a field left out is not changed."""

    model_config = ConfigDict(extra="forbid")

    locale: Locale | None = Field(default=None, description="the language of the patient's pages; null: the browser's",
                                  examples=["es"])  # fmt: skip
    pain_alert_above: int | None = Field(
        default=None,
        ge=0,
        le=9,
        description="therapists only: pain said after a set (0-10) above this raises the patient's attention score; "
        f"null: the default ({PAIN_ALERT_ABOVE})",
        examples=[4],
    )
