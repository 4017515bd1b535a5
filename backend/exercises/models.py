"""The built-in exercise library as a table (seeded from backend.exercises.library.LIBRARY)."""

from __future__ import annotations

import datetime as dt

from sqlalchemy import JSON, String, Text
from sqlalchemy.orm import Mapped, mapped_column

from backend.database import Base, utcnow


class Exercise(Base):
    """One exercise: defining angles (names from joint_angles), plane, normal range in degrees, start pose."""

    __tablename__ = "exercise"

    id: Mapped[int] = mapped_column(primary_key=True)
    slug: Mapped[str] = mapped_column(String(64), unique=True)
    name: Mapped[str] = mapped_column(String(200))
    instructions: Mapped[str] = mapped_column(Text, default="")
    defining_angles: Mapped[list[str]] = mapped_column(JSON, default=list)
    plane: Mapped[str] = mapped_column(String(32), default="")
    normal_range_min_deg: Mapped[float] = mapped_column()
    normal_range_max_deg: Mapped[float] = mapped_column()
    pose: Mapped[str] = mapped_column(String(64), default="")
    uiprmd_movement: Mapped[str | None] = mapped_column(String(16))
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)

    @property
    def mdc95_rom_deg(self) -> float | None:
        """The minimal detectable change of rom_deg, degrees (kinect_agent.analysis.mdc), or None when not measured."""
        from kinect_agent.analysis.mdc import rom_mdc95

        return rom_mdc95(self.slug)
