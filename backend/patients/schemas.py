"""Patient bodies."""

from __future__ import annotations

import datetime as dt
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from backend.reminders.times import zone
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
    time_zone: str | None = Field(default=None, description="IANA time zone of the patient's reminder times; null: "
                                  "the server's COACH_TIME_ZONE", examples=["Europe/Berlin"])  # fmt: skip
    reminder_emails: bool = Field(default=True, description="false once the patient used an e-mail's unsubscribe "
                                  "link (or their therapist turned e-mails off)")  # fmt: skip
    pain_alert_above: int = Field(
        default=PAIN_ALERT_ABOVE,
        description="pain said after a set (0-10) above this raises the patient's attention score "
        f"(set by the therapist; {PAIN_ALERT_ABOVE} unless set)",
        examples=[5],
    )


class PatientUpdate(BaseModel):
    """The patient or their therapist changes the patient's settings; only the fields sent change."""

    model_config = ConfigDict(extra="forbid")
    locale: Locale | None = Field(default=None, description="the language of the patient's pages; null: the "
                                  "browser's", examples=["es"])  # fmt: skip
    time_zone: str | None = Field(default=None, max_length=64, description="IANA time zone of the reminder times; "
                                  "null: the server's", examples=["Europe/Madrid"])  # fmt: skip
    reminder_emails: bool | None = Field(default=None, description="true: send reminder e-mails again; false: stop",
                                         examples=[True])  # fmt: skip
    pain_alert_above: int | None = Field(
        default=None,
        ge=0,
        le=9,
        description="therapists only: pain said after a set (0-10) above this raises the patient's attention score; "
        f"null: the default ({PAIN_ALERT_ABOVE})",
        examples=[4],
    )

    @field_validator("time_zone")
    @classmethod
    def _known_zone(cls, value: str | None) -> str | None:
        if value is not None:
            zone(value)  # ValueError naming the zone
        return value

    @model_validator(mode="after")
    def _something(self) -> PatientUpdate:
        if not self.model_fields_set:
            raise ValueError("send at least one of locale, time_zone, reminder_emails, pain_alert_above")
        if "reminder_emails" in self.model_fields_set and self.reminder_emails is None:
            raise ValueError("reminder_emails must be true or false")
        return self
