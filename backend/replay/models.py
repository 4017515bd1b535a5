"""The stored 3D replay recordings of a session (both skeletons, or one alone): built once by a worker, kept for
every server process."""

from __future__ import annotations

import datetime as dt

from sqlalchemy import ForeignKey, LargeBinary, String, UniqueConstraint
from sqlalchemy.orm import Mapped, deferred, mapped_column

from backend.database import Base, utcnow

BOTH = "raw,filtered"  # the layers of the replay page's default recording


class SessionReplay(Base):
    """The viser scene recording (`.viser` bytes, in the object store) of one session's skeletons `layers` ("raw",
    "filtered" or both, BOTH), by scene version `version`; one row per session and layers."""

    __tablename__ = "session_replay"
    __table_args__ = (UniqueConstraint("session_id", "layers"),)

    id: Mapped[int] = mapped_column(primary_key=True)
    session_id: Mapped[int] = mapped_column(ForeignKey("exercise_session.id", ondelete="CASCADE"))
    layers: Mapped[str] = mapped_column(String(20), default=BOTH, server_default=BOTH)
    version: Mapped[str] = mapped_column(String(32))
    data: Mapped[bytes | None] = deferred(mapped_column(LargeBinary))  # only before the move to the object store
    data_key: Mapped[str | None] = mapped_column(String(100))  # the recording in the object store (backend/storage)
    data_hash: Mapped[str | None] = mapped_column(String(64))  # its sha256
    size: Mapped[int] = mapped_column()
    n_frames: Mapped[int] = mapped_column()
    duration_s: Mapped[float] = mapped_column()
    view: Mapped[str] = mapped_column(String(8))
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
