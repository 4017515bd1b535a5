"""Exercise plans a therapist prescribes to a patient, and their items."""

from __future__ import annotations

import datetime as dt

from sqlalchemy import JSON, CheckConstraint, ForeignKey, String, Text
from sqlalchemy.orm import Mapped, mapped_column, relationship

from backend.database import Base, utcnow


class Plan(Base):
    """A prescription for one patient between start_date and end_date (inclusive; end open when None)."""

    __tablename__ = "plan"

    id: Mapped[int] = mapped_column(primary_key=True)
    patient_id: Mapped[int] = mapped_column(ForeignKey("user.id", ondelete="CASCADE"), index=True)
    therapist_id: Mapped[int | None] = mapped_column(ForeignKey("user.id", ondelete="SET NULL"), index=True)
    title: Mapped[str] = mapped_column(String(200))
    notes: Mapped[str] = mapped_column(Text, default="")  # the note to the patient, shown on the patient's page
    start_date: Mapped[dt.date] = mapped_column()
    end_date: Mapped[dt.date | None] = mapped_column()
    # reminder times of each plan day, "HH:MM" in the patient's time zone, sorted (backend/reminders)
    reminder_times: Mapped[list[str]] = mapped_column(JSON, default=list, server_default="[]")
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
    updated_at: Mapped[dt.datetime] = mapped_column(default=utcnow, onupdate=utcnow)

    items: Mapped[list[PlanItem]] = relationship(
        back_populates="plan", cascade="all, delete-orphan", order_by="PlanItem.position", lazy="selectin"
    )


class PlanItem(Base):
    """One prescribed exercise: sets x repetitions, frequency_per_week sessions per week, an optional target range
    of motion in degrees."""

    __tablename__ = "plan_item"
    __table_args__ = (
        CheckConstraint("sets > 0", name="sets_positive"),
        CheckConstraint("repetitions > 0", name="repetitions_positive"),
        CheckConstraint("frequency_per_week BETWEEN 1 AND 21", name="frequency_range"),
        CheckConstraint(
            "target_rom_deg IS NULL OR (target_rom_deg > 0 AND target_rom_deg <= 180)", name="target_rom_range"
        ),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    plan_id: Mapped[int] = mapped_column(ForeignKey("plan.id", ondelete="CASCADE"), index=True)
    exercise_id: Mapped[int] = mapped_column(ForeignKey("exercise.id", ondelete="RESTRICT"), index=True)
    position: Mapped[int] = mapped_column(default=0)
    sets: Mapped[int] = mapped_column()
    repetitions: Mapped[int] = mapped_column()
    frequency_per_week: Mapped[int] = mapped_column()
    target_rom_deg: Mapped[float | None] = mapped_column()
    notes: Mapped[str] = mapped_column(Text, default="")

    plan: Mapped[Plan] = relationship(back_populates="items")
