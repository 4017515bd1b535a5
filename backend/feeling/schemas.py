"""Request and response bodies of how a set felt."""

from __future__ import annotations

import datetime as dt

from pydantic import BaseModel, ConfigDict, Field


class FeelingIn(BaseModel):
    """The patient's answers after a set; null = skipped."""

    model_config = ConfigDict(extra="forbid")

    pain: int | None = Field(ge=0, le=10, description="pain, numeric rating scale 0 (none) to 10 (worst)", examples=[2])
    effort: float | None = Field(
        ge=0, le=10, multiple_of=0.5, examples=[3.5],
        description="effort, Borg CR10: 0 (nothing at all) to 10 (maximal), in halves",
    )  # fmt: skip


class FeelingOut(FeelingIn):
    """How a set felt (both null and answered_at null: not answered yet)."""

    session_id: int = Field(examples=[31])
    answered_at: dt.datetime | None = None
