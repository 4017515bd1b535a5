"""Coaching suggestions made by rules (source 'system') or therapists; router/service are E3's."""

from __future__ import annotations

import datetime as dt
from typing import Any

from sqlalchemy import JSON, CheckConstraint, ForeignKey, String, Text
from sqlalchemy.orm import Mapped, mapped_column

from backend.database import Base, utcnow

SOURCES = ("system", "therapist")
STATUSES = ("pending", "approved", "dismissed")


class Suggestion(Base):
    """One suggestion: which rule fired on which metric (comparison against threshold) and its text.

    A system suggestion keeps what its rule found (params, backend.suggestions.rules.AdviceParams) and is shown in
    the reader's language, written from params when read; text is the advice as first written, in the patient's
    language of that moment (what is shown when params is null: rows made before params existed). A therapist's
    text is shown as written."""

    __tablename__ = "suggestion"
    __table_args__ = (
        CheckConstraint("source IN ('system', 'therapist')", name="source"),
        CheckConstraint("status IN ('pending', 'approved', 'dismissed', 'superseded')", name="status"),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    patient_id: Mapped[int] = mapped_column(ForeignKey("user.id", ondelete="CASCADE"), index=True)
    session_id: Mapped[int | None] = mapped_column(ForeignKey("exercise_session.id", ondelete="SET NULL"), index=True)
    author_id: Mapped[int | None] = mapped_column(ForeignKey("user.id", ondelete="SET NULL"))
    source: Mapped[str] = mapped_column(String(16), default="system")
    rule: Mapped[str] = mapped_column(String(64), default="")
    metric: Mapped[str] = mapped_column(String(64), default="")
    comparison: Mapped[str] = mapped_column(String(8), default="")
    threshold: Mapped[float | None] = mapped_column()
    value: Mapped[float | None] = mapped_column()  # the measured value compared with threshold (system ones)
    text: Mapped[str] = mapped_column(Text)
    params: Mapped[dict[str, Any] | None] = mapped_column(JSON)  # what the rule found (AdviceParams); null: show text
    status: Mapped[str] = mapped_column(String(16), default="pending", index=True)
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
    decided_at: Mapped[dt.datetime | None] = mapped_column()
    decided_by_id: Mapped[int | None] = mapped_column(ForeignKey("user.id", ondelete="SET NULL"))
