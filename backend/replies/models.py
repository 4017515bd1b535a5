"""A patient's reply to one piece of advice: a preset answer, a few words, or both."""

from __future__ import annotations

import datetime as dt

from sqlalchemy import CheckConstraint, ForeignKey, Index, String
from sqlalchemy.orm import Mapped, mapped_column

from backend.database import Base, utcnow

PRESETS = ("done", "hurt", "call_me")  # "Done", "It hurt", "Call me"
MAX_TEXT = 500  # characters of a written reply


class AdviceReply(Base):
    """One reply from the patient to a suggestion; read_at is set when the therapist side has read it."""

    __tablename__ = "advice_reply"
    __table_args__ = (
        CheckConstraint("preset IN ('done', 'hurt', 'call_me')", name="preset"),
        CheckConstraint("preset IS NOT NULL OR text IS NOT NULL", name="says_something"),
        Index("ix_advice_reply_patient_id_read_at", "patient_id", "read_at"),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    suggestion_id: Mapped[int] = mapped_column(ForeignKey("suggestion.id", ondelete="CASCADE"), index=True)
    patient_id: Mapped[int] = mapped_column(ForeignKey("user.id", ondelete="CASCADE"))
    preset: Mapped[str | None] = mapped_column(String(16))
    text: Mapped[str | None] = mapped_column(String(MAX_TEXT))
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
    read_at: Mapped[dt.datetime | None] = mapped_column()  # null: no therapist or admin has read it yet
    read_by_id: Mapped[int | None] = mapped_column(ForeignKey("user.id", ondelete="SET NULL"))
