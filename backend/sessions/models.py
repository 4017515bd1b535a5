"""Performed exercise sets uploaded by home devices, and their metrics (router/service are E3's)."""

from __future__ import annotations

import datetime as dt
import uuid
from typing import Any

from sqlalchemy import JSON, Boolean, ForeignKey, Index, LargeBinary, String, Text, UniqueConstraint
from sqlalchemy.orm import Mapped, deferred, mapped_column, relationship

from backend.database import Base, utcnow


class ExerciseSession(Base):
    """One performed set: the uploaded session file (deferred), its sha256 and how it was processed."""

    __tablename__ = "exercise_session"
    __table_args__ = (
        UniqueConstraint("patient_id", "client_session_id"),
        # newest-first reads per patient (dashboard, session lists); migration 0002
        Index("ix_exercise_session_patient_id_started_at", "patient_id", "started_at", "id"),
    )

    id: Mapped[int] = mapped_column(primary_key=True)
    client_session_id: Mapped[uuid.UUID] = mapped_column()
    patient_id: Mapped[int] = mapped_column(ForeignKey("user.id", ondelete="CASCADE"), index=True)
    device_id: Mapped[int | None] = mapped_column(ForeignKey("device.id", ondelete="SET NULL"), index=True)
    exercise_id: Mapped[int | None] = mapped_column(ForeignKey("exercise.id", ondelete="RESTRICT"), index=True)
    started_at: Mapped[dt.datetime] = mapped_column(index=True)
    duration_s: Mapped[float] = mapped_column()
    n_frames: Mapped[int] = mapped_column()
    file_name: Mapped[str | None] = mapped_column(String(255))
    file_format: Mapped[str | None] = mapped_column(String(32))
    # the file is in the object store under file_key (backend/storage), its sha256 = content_hash; file_bytes only
    # holds files of databases not yet moved out (migration 0011, `coach-server storage move-out`)
    file_bytes: Mapped[bytes | None] = deferred(mapped_column(LargeBinary))
    file_key: Mapped[str | None] = mapped_column(String(100))
    file_size: Mapped[int] = mapped_column(default=0)
    # when the retention period removed the file (backend/records/retention.py): the session's tombstone; the row
    # and its metrics stay
    file_removed_at: Mapped[dt.datetime | None] = mapped_column()
    content_hash: Mapped[str] = mapped_column(String(64), index=True)
    processing_version: Mapped[str] = mapped_column(String(64), default="")
    processing_params: Mapped[dict[str, Any]] = mapped_column(JSON, default=dict[str, Any])
    status: Mapped[str] = mapped_column(String(16), default="processed")
    error: Mapped[str | None] = mapped_column(Text)
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)

    metric: Mapped[SessionMetric | None] = relationship(
        back_populates="session", cascade="all, delete-orphan", uselist=False
    )


class SessionMetric(Base):
    """All metrics of one session as a JSON document, plus a few indexed scalars for queries."""

    __tablename__ = "session_metric"

    id: Mapped[int] = mapped_column(primary_key=True)
    session_id: Mapped[int] = mapped_column(ForeignKey("exercise_session.id", ondelete="CASCADE"), unique=True)
    document: Mapped[dict[str, Any]] = mapped_column(JSON, default=dict[str, Any])
    repetitions: Mapped[int | None] = mapped_column(index=True)
    rom_deg: Mapped[float | None] = mapped_column()
    quality_ok: Mapped[bool | None] = mapped_column(Boolean, index=True)
    # {indicator: score} copied from document["indicators"] (migration 0007): the dashboard reads weeks of these
    indicator_scores: Mapped[dict[str, Any] | None] = mapped_column(JSON)
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)

    session: Mapped[ExerciseSession] = relationship(back_populates="metric")


class SessionDetail(Base):
    """The session page's evidence (backend.sessions.detail: curves, repetitions, quality …) built once by a worker,
    as JSON in the object store; `inputs` is the sha256 of what it was made from (the file, the exercise, the
    metrics document, the detail's version), so a re-analysis or a new version makes it stale."""

    __tablename__ = "session_detail"

    id: Mapped[int] = mapped_column(primary_key=True)
    session_id: Mapped[int] = mapped_column(ForeignKey("exercise_session.id", ondelete="CASCADE"), unique=True)
    inputs: Mapped[str] = mapped_column(String(64))
    data_key: Mapped[str] = mapped_column(String(100))  # the JSON document in the object store (backend/storage)
    data_hash: Mapped[str] = mapped_column(String(64))  # its sha256
    size: Mapped[int] = mapped_column()
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)


class SessionExport(Base):
    """A session's download in one format (csv, trc, bvh, fhir) built once by a worker, its bytes in the object
    store; `inputs` is the sha256 of what it was made from (backend.sessions.prepared_export.inputs_of), so a
    re-analysis, a new answer about how the set felt or a new exporter version makes it stale."""

    __tablename__ = "session_export"
    __table_args__ = (UniqueConstraint("session_id", "format"),)

    id: Mapped[int] = mapped_column(primary_key=True)
    session_id: Mapped[int] = mapped_column(ForeignKey("exercise_session.id", ondelete="CASCADE"))
    format: Mapped[str] = mapped_column(String(8))
    inputs: Mapped[str] = mapped_column(String(64))
    data_key: Mapped[str] = mapped_column(String(100))  # the file gzip-compressed in the object store (backend/storage)
    data_hash: Mapped[str] = mapped_column(String(64))  # the sha256 of the stored (compressed) bytes
    size: Mapped[int] = mapped_column()  # of the stored (compressed) bytes
    media_type: Mapped[str] = mapped_column(String(64))  # the download's Content-Type
    file_name: Mapped[str] = mapped_column(String(100))  # the download's name, e.g. session-12.bvh
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
