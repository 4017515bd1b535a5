"""Reply bodies: what the patient sends, a stored reply as the API shows it, and marking replies read."""

from __future__ import annotations

import datetime as dt
from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from backend.replies.models import MAX_TEXT
from backend.schemas import MAX_ID

Preset = Literal["done", "hurt", "call_me"]  # the buttons "Done", "It hurt", "Call me"
MAX_MARKED = 200  # reply ids marked read in one request


class ReplyIn(BaseModel):
    """The patient's answer to one piece of advice: a preset, a few words, or both (at least one)."""

    model_config = ConfigDict(extra="forbid")
    suggestion_id: int = Field(ge=1, le=MAX_ID, description="the advice answered", examples=[7])
    preset: Preset | None = Field(default=None, examples=["hurt"])
    text: str | None = Field(default=None, min_length=1, max_length=MAX_TEXT, examples=["My knee hurt on the third."])

    @field_validator("text")
    @classmethod
    def _not_blank(cls, value: str | None) -> str | None:
        if value is None:
            return None
        value = value.strip()
        if not value:
            raise ValueError("text must not be blank")
        return value  # NUL characters are refused for every JSON body (backend/request_limits.py)

    @model_validator(mode="after")
    def _says_something(self) -> ReplyIn:
        if self.preset is None and self.text is None:
            raise ValueError("give a preset, a text, or both")
        return self


class ReplyOut(BaseModel):
    """A stored reply, with the advice it answers."""

    model_config = ConfigDict(from_attributes=True)
    id: int = Field(examples=[3])
    patient_id: int = Field(examples=[12])
    suggestion_id: int = Field(examples=[7])
    suggestion_text: str = Field(description="the advice answered", examples=["Hold the top of each squat."])
    preset: Preset | None = Field(examples=["hurt"])
    text: str | None = Field(examples=["My knee hurt on the third."])
    created_at: dt.datetime
    read_at: dt.datetime | None = Field(description="when a therapist or admin read it; null: unread")
    read_by_id: int | None


class ReadIn(BaseModel):
    """The replies a therapist has seen (only these are marked read, so one arriving meanwhile stays unread)."""

    model_config = ConfigDict(extra="forbid")
    reply_ids: list[int] = Field(min_length=1, max_length=MAX_MARKED, examples=[[3, 4]])

    @field_validator("reply_ids")
    @classmethod
    def _ids(cls, value: list[int]) -> list[int]:
        if any(not 1 <= i <= MAX_ID for i in value):
            raise ValueError(f"every id must be between 1 and {MAX_ID}")
        return value


class ReadOut(BaseModel):
    """How many of the replies were unread and are read now."""

    marked: int = Field(ge=0, examples=[2])
