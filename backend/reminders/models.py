"""The reminder e-mails claimed or sent: one row per plan, patient-local day and reminder time."""

from __future__ import annotations

import datetime as dt

from sqlalchemy import ForeignKey, String, Text, UniqueConstraint
from sqlalchemy.orm import Mapped, mapped_column

from backend.database import Base, utcnow


class ReminderSent(Base):
    """One reminder e-mail: inserted before sending (the unique key lets only one server send it), sent_at set after.

    token_hash is the SHA-256 of the e-mail's unsubscribe token (the token itself is only in the e-mail).
    """

    __tablename__ = "reminder_sent"
    __table_args__ = (UniqueConstraint("plan_id", "local_date", "local_time"),)

    id: Mapped[int] = mapped_column(primary_key=True)
    plan_id: Mapped[int] = mapped_column(ForeignKey("plan.id", ondelete="CASCADE"))
    patient_id: Mapped[int] = mapped_column(ForeignKey("user.id", ondelete="CASCADE"), index=True)
    local_date: Mapped[dt.date] = mapped_column()  # the day in the patient's time zone
    local_time: Mapped[str] = mapped_column(String(5))  # "HH:MM" in the patient's time zone
    due_at: Mapped[dt.datetime] = mapped_column()  # the same instant in UTC
    token_hash: Mapped[str] = mapped_column(String(64), unique=True)
    claimed_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
    sent_at: Mapped[dt.datetime | None] = mapped_column()
    error: Mapped[str | None] = mapped_column(Text)
