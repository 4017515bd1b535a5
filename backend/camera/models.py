"""The rows of camera sets: a patient's consent, each set the server started, and the landmark batches sent."""

from __future__ import annotations

import datetime as dt
import uuid

from sqlalchemy import ForeignKey, LargeBinary, String, Text, UniqueConstraint
from sqlalchemy.orm import Mapped, deferred, mapped_column

from backend.database import Base, utcnow


class CameraConsent(Base):
    """A patient's consent to record sets with their own camera: which consent text (version) and when."""

    __tablename__ = "camera_consent"

    patient_id: Mapped[int] = mapped_column(ForeignKey("user.id", ondelete="CASCADE"), primary_key=True)
    consent_version: Mapped[str] = mapped_column(String(16))
    given_at: Mapped[dt.datetime] = mapped_column(default=utcnow)


class CameraSet(Base):
    """One set the server started for a plan item of a patient; status recording -> stored | failed.

    n_frames, last_seq (-1 before the first batch) and last_t (s, the set's clock) follow the batches received;
    session_id is the stored session once the set ended.
    """

    __tablename__ = "camera_set"

    id: Mapped[uuid.UUID] = mapped_column(primary_key=True)
    patient_id: Mapped[int] = mapped_column(ForeignKey("user.id", ondelete="CASCADE"), index=True)
    plan_item_id: Mapped[int | None] = mapped_column(ForeignKey("plan_item.id", ondelete="SET NULL"), index=True)
    exercise_id: Mapped[int] = mapped_column(ForeignKey("exercise.id", ondelete="RESTRICT"), index=True)
    target_reps: Mapped[int] = mapped_column()
    model_name: Mapped[str] = mapped_column(String(64))
    status: Mapped[str] = mapped_column(String(16), default="recording")
    n_frames: Mapped[int] = mapped_column(default=0)
    n_batches: Mapped[int] = mapped_column(default=0)
    last_seq: Mapped[int] = mapped_column(default=-1)
    last_t: Mapped[float | None] = mapped_column()
    started_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
    ended_at: Mapped[dt.datetime | None] = mapped_column()
    end_reason: Mapped[str | None] = mapped_column(String(16))
    session_id: Mapped[int | None] = mapped_column(ForeignKey("exercise_session.id", ondelete="SET NULL"))
    error: Mapped[str | None] = mapped_column(Text)


class CameraBatch(Base):
    """One batch of landmarks of a set, as received: its number, frame count and times, and its arrays.

    data: zlib of float64 t (T,) s, then float32 world (T, 33, 3) m, image (T, 33, 3) normalised and visibility
    (T, 33), in this order (backend.camera.batch.pack); content_hash: SHA-256 of data, so a re-sent batch is told
    from a different one with the same number.
    """

    __tablename__ = "camera_batch"
    __table_args__ = (UniqueConstraint("set_id", "seq"),)

    id: Mapped[int] = mapped_column(primary_key=True)
    set_id: Mapped[uuid.UUID] = mapped_column(ForeignKey("camera_set.id", ondelete="CASCADE"), index=True)
    seq: Mapped[int] = mapped_column()
    n_frames: Mapped[int] = mapped_column()
    t_first: Mapped[float] = mapped_column()
    t_last: Mapped[float] = mapped_column()
    image_width: Mapped[int] = mapped_column()
    image_height: Mapped[int] = mapped_column()
    content_hash: Mapped[str] = mapped_column(String(64))
    data: Mapped[bytes] = deferred(mapped_column(LargeBinary, nullable=False))
    received_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
