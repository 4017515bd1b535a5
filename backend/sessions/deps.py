"""Request parameters the session routers share (backend.sessions.router, backend.session_review.router)."""

from __future__ import annotations

from typing import Annotated

from fastapi import Query

SlugQuery = Annotated[
    str | None, Query(min_length=1, max_length=64, description="exercise slug, e.g. 'squat'", examples=["squat"])
]
