"""A patient's archive built by a worker and kept in the object store."""

from __future__ import annotations

import datetime as dt

from sqlalchemy import BigInteger, ForeignKey, String
from sqlalchemy.orm import Mapped, mapped_column

from backend.database import Base, utcnow


class PatientArchive(Base):
    """The last archive of everything held about one patient (backend.records.archive), built once by a worker
    (backend.records.prepared_archive), its zip in the object store. `covers` is the sha256 of the patient's data it
    was made from (prepared_archive.covers_of: sessions, metrics, plans, advice, replies, devices, settings ...), so
    a new session or any change makes it stale and the next ask builds a new one; the audit log is not part of it
    (every ask adds to it): an archive holds the audit entries up to made_at."""

    __tablename__ = "patient_archive"

    id: Mapped[int] = mapped_column(primary_key=True)
    patient_id: Mapped[int] = mapped_column(ForeignKey("user.id", ondelete="CASCADE"), unique=True)
    covers: Mapped[str] = mapped_column(String(64))
    sessions: Mapped[int] = mapped_column()  # the sessions it holds
    incomplete: Mapped[int] = mapped_column()  # of those, the sessions lacking their file or an export (README.txt)
    data_key: Mapped[str] = mapped_column(String(100))  # the zip in the object store (backend/storage)
    data_hash: Mapped[str] = mapped_column(String(64))  # the sha256 of the zip
    size: Mapped[int] = mapped_column(BigInteger)  # bytes of the zip
    file_name: Mapped[str] = mapped_column(String(100))  # the download's name, patient-12-data-20261127.zip
    made_at: Mapped[dt.datetime] = mapped_column(default=utcnow)
