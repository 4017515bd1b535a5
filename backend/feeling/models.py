"""How a set felt to the patient: pain on the 0-10 numeric rating scale and effort on the Borg CR10 scale."""

from __future__ import annotations

import datetime as dt

from sqlalchemy import ForeignKey
from sqlalchemy.orm import Mapped, mapped_column

from backend.database import Base, utcnow


class SessionFeeling(Base):
    """The patient's answer after one set (one row per session; a skipped question is null)."""

    __tablename__ = "session_feeling"

    session_id: Mapped[int] = mapped_column(ForeignKey("exercise_session.id", ondelete="CASCADE"), primary_key=True)
    pain_nrs: Mapped[int | None] = mapped_column()  # 0 no pain .. 10 worst pain imaginable
    effort_cr10: Mapped[float | None] = mapped_column()  # Borg CR10: 0 nothing at all .. 10 maximal, halves allowed
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
    updated_at: Mapped[dt.datetime] = mapped_column(default=utcnow, onupdate=utcnow)
