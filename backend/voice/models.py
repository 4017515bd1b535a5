"""A patient's spoken feedback during a live set: on or off, and how loud (one row per patient; none = defaults)."""

from __future__ import annotations

import datetime as dt

from sqlalchemy import ForeignKey
from sqlalchemy.orm import Mapped, mapped_column

from backend.database import Base, utcnow

DEFAULT_ENABLED = True  # patients hear the set by default (issue 23: they may be 3 m from the screen)
DEFAULT_VOLUME = 1.0


class VoicePreference(Base):
    """Whether the patient's page speaks during a live set, and its volume (0..1, the speech synthesis's scale)."""

    __tablename__ = "voice_preference"

    patient_id: Mapped[int] = mapped_column(ForeignKey("user.id", ondelete="CASCADE"), primary_key=True)
    enabled: Mapped[bool] = mapped_column(default=DEFAULT_ENABLED)
    volume: Mapped[float] = mapped_column(default=DEFAULT_VOLUME)
    updated_at: Mapped[dt.datetime] = mapped_column(default=utcnow, onupdate=utcnow)
    updated_by_id: Mapped[int | None] = mapped_column(ForeignKey("user.id", ondelete="SET NULL"))
