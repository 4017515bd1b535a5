"""Suggestion bodies: what a therapist writes, and a stored suggestion as the API shows it."""

from __future__ import annotations

import datetime as dt
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator

from backend.schemas import MAX_ID

Status = Literal["pending", "approved", "dismissed", "superseded"]  # superseded: newer advice of the same rule
Source = Literal["system", "therapist"]


class SuggestionIn(BaseModel):
    """A suggestion a therapist writes to a patient, optionally about one session."""

    model_config = ConfigDict(extra="forbid")
    text: str = Field(
        min_length=1,
        max_length=2000,
        examples=["Well done this week! Tomorrow, try to hold the top of each squat for two seconds."],
    )
    session_id: int | None = Field(default=None, ge=1, le=MAX_ID, examples=[None])

    @field_validator("text")
    @classmethod
    def _not_blank(cls, value: str) -> str:
        value = value.strip()
        if not value:
            raise ValueError("text must not be blank")
        return value  # NUL characters are refused for every JSON body (backend/request_limits.py)


class SuggestionOut(BaseModel):
    """A stored suggestion. System ones name the rule and the check `metric value comparison threshold` that fired."""

    model_config = ConfigDict(
        from_attributes=True,
        json_schema_extra={
            "examples": [
                {
                    "id": 7,
                    "patient_id": 12,
                    "session_id": 31,
                    "session_started_at": "2026-11-21T09:30:00Z",
                    "source": "system",
                    "author_id": None,
                    "rule": "fewer_reps",
                    "metric": "repetitions",
                    "comparison": "<",
                    "threshold": 10.0,
                    "value": 6.0,
                    "text": "On Saturday you did 6 of the 10 sit-to-stands in your plan. Next time, try to do all "
                    "10. Rest for a moment between them if you need to.",
                    "locale": "en",
                    "status": "pending",
                    "created_at": "2026-11-23T10:00:00Z",
                    "decided_at": None,
                    "decided_by_id": None,
                }
            ]
        },
    )
    id: int
    patient_id: int
    session_id: int | None
    session_started_at: dt.datetime | None = Field(
        default=None, description="when the session the advice is about started (null: not about one session)"
    )
    source: Source
    author_id: int | None = Field(description="the therapist or admin who wrote it (therapist suggestions)")
    rule: str = Field(description="the rule that fired (system), 'therapist' otherwise")
    metric: str = Field(description="the metric the rule checked, e.g. 'rom_deg'; empty for therapist ones")
    comparison: str = Field(description="how the metric compared to the threshold: '<', '>' or '=='")
    threshold: float | None
    value: float | None = Field(description="the measured value of the metric that fired: value comparison threshold")
    text: str = Field(
        description="the advice, in words the patient understands: a rule's advice is written when read, in the "
        "language the request's Accept-Language asks for, else the patient's; a therapist's as written"
    )
    locale: str | None = Field(
        default=None, description="the language of text when it was written for this reader ('en', 'de', 'es', "
        "'fr'); null: as its author wrote it (a therapist's, or a rule's stored before 2026-11-27)"
    )  # fmt: skip
    status: Status
    created_at: dt.datetime
    decided_at: dt.datetime | None = Field(description="when it was approved or dismissed")
    decided_by_id: int | None
