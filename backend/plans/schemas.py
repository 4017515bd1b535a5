"""Plan bodies."""

from __future__ import annotations

import datetime as dt
from typing import ClassVar

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from backend.reminders.times import MAX_REMINDERS_PER_DAY, normalise_times
from backend.schemas import BodyRule

REMINDER_TIME_PATTERN = r"^([01][0-9]|2[0-3]):[0-5][0-9]$"  # what the document promises (the server also strips blanks)
END_NOT_BEFORE_START = BodyRule(
    "EndDateBeforeStartDate",
    "end_date, when given, is start_date or later",
    "end_date must not be before start_date",
)


class PlanItemIn(BaseModel):
    """One prescribed exercise."""

    exercise_slug: str = Field(min_length=1, max_length=64, examples=["deep_squat"])
    sets: int = Field(ge=1, le=100, examples=[3])
    repetitions: int = Field(ge=1, le=1000, examples=[10])
    frequency_per_week: int = Field(ge=1, le=21, examples=[3])
    target_rom_deg: float | None = Field(
        default=None, gt=0, le=180, description="Target range of motion, degrees (None: no target)", examples=[90]
    )
    notes: str = Field(default="", max_length=2000)


class PlanIn(BaseModel):
    """A plan as a therapist writes it (PUT replaces every field and item). end_date, when given, is start_date or
    later: an earlier one is answered 422 ValidationError (x-body-rules)."""

    body_rules: ClassVar[tuple[BodyRule, ...]] = (END_NOT_BEFORE_START,)
    model_config = ConfigDict(json_schema_extra={"x-body-rules": [END_NOT_BEFORE_START.as_schema()]})

    title: str = Field(min_length=1, max_length=200, examples=["Knee rehab, weeks 1-4"])
    notes: str = Field(
        default="",
        max_length=5000,
        description="The note to the patient, shown on the patient's page",
        examples=["Take a short rest between the two sets."],
    )
    start_date: dt.date = Field(examples=["2026-11-23"])
    end_date: dt.date | None = Field(default=None, examples=["2026-12-21"],
                                     description="start_date or later (422 ValidationError otherwise, x-body-rules "
                                     "EndDateBeforeStartDate); null: no end")  # fmt: skip
    items: list[PlanItemIn] = Field(default_factory=list, max_length=50)
    reminder_times: list[str] = Field(
        default_factory=list,
        max_length=MAX_REMINDERS_PER_DAY,
        description="reminder times of each plan day, HH:MM (24-hour clock) in the patient's time zone, each once",
        examples=[["08:30", "18:00"]],
        json_schema_extra={"uniqueItems": True, "items": {"type": "string", "pattern": REMINDER_TIME_PATTERN}},
    )

    @field_validator("reminder_times")
    @classmethod
    def _reminder_times(cls, value: list[str]) -> list[str]:
        return normalise_times(value)

    @field_validator("items")
    @classmethod
    def _each_exercise_once(cls, items: list[PlanItemIn]) -> list[PlanItemIn]:
        first: dict[str, int] = {}
        for i, item in enumerate(items):
            slug = item.exercise_slug
            if slug in first:
                raise ValueError(
                    f"exercise {slug!r} is in the plan twice (items {first[slug]} and {i}): give each exercise once, "
                    "with more sets if needed"
                )
            first[slug] = i
        return items

    @field_validator("start_date", "end_date", mode="before")
    @classmethod
    def _a_date_text(cls, value: object) -> object:
        """Refuses numbers (pydantic would read 0 as 1970-01-01): a date is written as text, YYYY-MM-DD."""
        if isinstance(value, int | float):
            raise ValueError("must be a date written as text, YYYY-MM-DD (not a number)")
        return value

    @model_validator(mode="after")
    def _dates_in_order(self) -> PlanIn:
        if self.end_date is not None and self.end_date < self.start_date:
            raise ValueError(END_NOT_BEFORE_START.message)
        return self


class PlanItemOut(BaseModel):
    """One prescribed exercise of a stored plan."""

    model_config = ConfigDict(from_attributes=True)
    id: int = Field(examples=[41])
    exercise_id: int = Field(examples=[5])
    exercise_slug: str = Field(examples=["seated_knee_extension"])
    position: int = Field(examples=[0])
    sets: int = Field(examples=[2])
    repetitions: int = Field(examples=[10])
    frequency_per_week: int = Field(examples=[3])
    target_rom_deg: float | None = Field(examples=[90])
    notes: str = Field(examples=["Slowly, both legs"])


class PlanOut(BaseModel):
    """A stored plan."""

    id: int = Field(examples=[17])
    patient_id: int = Field(examples=[12])
    therapist_id: int | None = Field(examples=[2])
    therapist_name: str | None = Field(
        description="Who prescribed the plan (None: an admin)", examples=["Tara Therapist"]
    )
    title: str = Field(examples=["Knee rehab, weeks 1-4"])
    notes: str = Field(examples=[""])
    start_date: dt.date = Field(examples=["2026-11-23"])
    end_date: dt.date | None = Field(examples=["2026-12-21"])
    created_at: dt.datetime = Field(examples=["2026-11-23T09:00:00Z"])
    updated_at: dt.datetime = Field(examples=["2026-11-23T09:00:00Z"])
    items: list[PlanItemOut]
    reminder_times: list[str] = Field(description="HH:MM in the patient's time zone, sorted", examples=[["08:30"]])
