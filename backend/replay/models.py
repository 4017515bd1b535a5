"""The stored 3D replay recording of a session: built once, kept in the database so every worker serves it."""

from __future__ import annotations

import datetime as dt

from sqlalchemy import ForeignKey, LargeBinary, String
from sqlalchemy.orm import Mapped, deferred, mapped_column

from backend.database import Base, utcnow


class SessionReplay(Base):
    """The viser scene recording (`.viser` bytes, in the object store) of one session, by scene version `version`."""

    __tablename__ = "session_replay"

    id: Mapped[int] = mapped_column(primary_key=True)
    session_id: Mapped[int] = mapped_column(ForeignKey("exercise_session.id", ondelete="CASCADE"), unique=True)
    version: Mapped[str] = mapped_column(String(32))
    data: Mapped[bytes | None] = deferred(mapped_column(LargeBinary))  # only before the move to the object store
    data_key: Mapped[str | None] = mapped_column(String(100))  # the recording in the object store (backend/storage)
    data_hash: Mapped[str | None] = mapped_column(String(64))  # its sha256
    size: Mapped[int] = mapped_column()
    n_frames: Mapped[int] = mapped_column()
    duration_s: Mapped[float] = mapped_column()
    view: Mapped[str] = mapped_column(String(8))
    created_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
