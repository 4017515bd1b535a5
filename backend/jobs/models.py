"""Queued work and the metrics documents a re-analysis replaced."""

from __future__ import annotations

import datetime as dt
from typing import Any

from sqlalchemy import JSON, ForeignKey, Index, String, Text
from sqlalchemy.orm import Mapped, mapped_column

from backend.database import Base, utcnow

MAX_ATTEMPTS = 3  # tries of a job before it is marked failed


class Job(Base):
    """One unit of work: queued → running (leased by a worker until locked_until) → done or failed.

    key is unique: enqueuing the same work twice keeps one job. A running job whose lease expired (its worker
    died) is taken again; a failing job is retried after a growing delay until max_attempts.
    """

    __tablename__ = "job"
    __table_args__ = (Index("ix_job_status_run_after", "status", "run_after"),)

    id: Mapped[int] = mapped_column(primary_key=True)
    kind: Mapped[str] = mapped_column(String(32))
    key: Mapped[str] = mapped_column(String(200), unique=True)
    batch: Mapped[str | None] = mapped_column(String(64), index=True)  # jobs enqueued together, for progress
    payload: Mapped[dict[str, Any]] = mapped_column(JSON, default=dict[str, Any])
    status: Mapped[str] = mapped_column(String(16), default="queued")
    attempts: Mapped[int] = mapped_column(default=0)
    max_attempts: Mapped[int] = mapped_column(default=MAX_ATTEMPTS)
    run_after: Mapped[dt.datetime] = mapped_column(default=utcnow)
    locked_by: Mapped[str | None] = mapped_column(String(100))
    locked_until: Mapped[dt.datetime | None] = mapped_column()
    result: Mapped[dict[str, Any] | None] = mapped_column(JSON)
    error: Mapped[str | None] = mapped_column(Text)
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
    finished_at: Mapped[dt.datetime | None] = mapped_column()


class SessionMetricVersion(Base):
    """A metrics document a re-analysis replaced, kept with the analysis version that made it and the session file
    it was computed from: file_key/file_hash (the object store's key and sha256; the session's current file unless a
    re-analysis filtered the raw recording again, then the earlier file, kept in the store) and processing_params
    (that file's params: the pipeline version and settings that filtered it). The three are null on rows replaced
    before migration reanalyzeraw_0018, and file_key is null once the retention period removed the file.
    document is {"error": ...} (analysis_version NO_METRICS) when the session had no metrics, its analysis failed."""

    __tablename__ = "session_metric_version"

    id: Mapped[int] = mapped_column(primary_key=True)
    session_id: Mapped[int] = mapped_column(ForeignKey("exercise_session.id", ondelete="CASCADE"), index=True)
    analysis_version: Mapped[str] = mapped_column(String(64))
    document: Mapped[dict[str, Any]] = mapped_column(JSON)
    replaced_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
    file_key: Mapped[str | None] = mapped_column(String(100))
    file_hash: Mapped[str | None] = mapped_column(String(64))
    processing_params: Mapped[dict[str, Any] | None] = mapped_column(JSON)
