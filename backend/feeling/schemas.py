"""Request and response bodies of how a set felt."""

from __future__ import annotations

import datetime as dt

from pydantic import BaseModel, ConfigDict, Field, field_validator


class FeelingIn(BaseModel):
    """The patient's answers after a set; null = skipped."""

    model_config = ConfigDict(extra="forbid")

    pain: int | None = Field(ge=0, le=10, description="pain, numeric rating scale 0 (none) to 10 (worst)", examples=[2])
    effort: float | None = Field(
        ge=0, le=10, description="effort, Borg CR10: 0 (nothing at all) to 10 (maximal), in halves", examples=[3.5]
    )

    @field_validator("effort")
    @classmethod
    def _halves(cls, value: float | None) -> float | None:
        if value is not None and (value * 2) != int(value * 2):
            raise ValueError("must be a whole or half number (Borg CR10)")
        return value


class FeelingOut(FeelingIn):
    """How a set felt (both null and answered_at null: not answered yet)."""

    session_id: int = Field(examples=[31])
    answered_at: dt.datetime | None = None
