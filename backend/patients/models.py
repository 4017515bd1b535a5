"""Therapist-patient assignment (a patient is a user with role 'patient')."""

from __future__ import annotations

import datetime as dt

from sqlalchemy import ForeignKey
from sqlalchemy.orm import Mapped, mapped_column

from backend.database import Base, utcnow


class TherapistPatient(Base):
    """Assigns one patient to one therapist; a patient may have several therapists."""

    __tablename__ = "therapist_patient"

    therapist_id: Mapped[int] = mapped_column(ForeignKey("user.id", ondelete="CASCADE"), primary_key=True)
    patient_id: Mapped[int] = mapped_column(ForeignKey("user.id", ondelete="CASCADE"), primary_key=True, index=True)
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
