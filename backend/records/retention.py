"""The retention period: session files (and their replays) older than it are removed; their metrics are kept.

A removed file leaves a tombstone: the session row keeps its metadata and metrics and records when the file went
(file_removed_at), so its pages and the API say "removed on DATE under the clinic's retention policy" (410).

Off by default (COACH_RETENTION_DAYS = 0). `coach-server retention` applies it (daily, from cron or the compose
worker); each patient whose files went gets one audit row "session.files_expired" with the count and the cut-off.
"""

from __future__ import annotations

import datetime as dt
from collections import Counter
from dataclasses import dataclass

from sqlalchemy import delete, or_, select, update
from sqlalchemy.orm import Session

from backend.audit.service import record
from backend.jobs.models import SessionMetricVersion
from backend.records.erasure import delete_after_commit, earlier_file_keys, unnamed_keys
from backend.records.models import PatientArchive
from backend.replay.models import SessionReplay
from backend.sessions.models import ExerciseSession, SessionDetail, SessionExport


@dataclass
class RetentionReport:
    """Files removed per patient id, the cut-off (UTC) and the objects deleted after commit."""

    cutoff: dt.datetime
    per_patient: dict[int, int]
    objects: list[str]

    def text(self) -> str:
        """Returns the report in words."""
        n = sum(self.per_patient.values())
        return (f"{n} session file(s) of {len(self.per_patient)} patient(s) started before "
                f"{self.cutoff:%Y-%m-%d %H:%M} UTC removed; their metrics are kept")  # fmt: skip


def apply_retention(*, db_session: Session, days: int, now: dt.datetime | None = None) -> RetentionReport:
    """Removes the files and replays of sessions started more than `days` days before now, and the built archives
    of their patients (which hold the files; the next ask builds one without them); flushes, never commits.

    Raises ValueError when days < 1 (retention off is 0: the caller does not call this).
    """
    if days < 1:
        raise ValueError(f"days must be at least 1, got {days}")
    now = now or dt.datetime.now(dt.UTC)
    cutoff = now - dt.timedelta(days=days)
    has_file = or_(ExerciseSession.file_key.is_not(None), ExerciseSession.file_bytes.is_not(None))
    rows = db_session.execute(
        select(ExerciseSession.id, ExerciseSession.patient_id, ExerciseSession.file_key).where(
            ExerciseSession.started_at < cutoff, has_file
        )
    ).all()
    ids = [r.id for r in rows]
    keys = {r.file_key for r in rows if r.file_key}
    keys |= {
        k for k in db_session.scalars(select(SessionReplay.data_key).where(SessionReplay.session_id.in_(ids))) if k
    }
    keys |= set(db_session.scalars(select(SessionDetail.data_key).where(SessionDetail.session_id.in_(ids))))
    keys |= set(db_session.scalars(select(SessionExport.data_key).where(SessionExport.session_id.in_(ids))))
    keys |= earlier_file_keys(db_session, ids)  # the files a re-analysis replaced go with the current one
    holders = PatientArchive.patient_id.in_({r.patient_id for r in rows})  # their archives hold the removed files
    keys |= set(db_session.scalars(select(PatientArchive.data_key).where(holders)))
    db_session.execute(delete(PatientArchive).where(holders))
    db_session.execute(delete(SessionReplay).where(SessionReplay.session_id.in_(ids)))
    db_session.execute(delete(SessionDetail).where(SessionDetail.session_id.in_(ids)))  # curves of the recording
    db_session.execute(delete(SessionExport).where(SessionExport.session_id.in_(ids)))  # downloads of the recording
    db_session.execute(
        update(ExerciseSession)
        .where(ExerciseSession.id.in_(ids))
        .values(file_key=None, file_bytes=None, file_removed_at=now)
    )
    db_session.execute(
        update(SessionMetricVersion).where(SessionMetricVersion.session_id.in_(ids)).values(file_key=None)
    )  # their sha256 stays: which file each earlier metrics came from
    objects = unnamed_keys(db_session, keys)
    per_patient = dict(Counter(r.patient_id for r in rows))
    for pid, n in per_patient.items():
        record(db_session=db_session, caller=None, action="session.files_expired", object_type="patient",
               object_id=pid, patient_id=pid,
               detail={"files": n, "retention_days": days, "started_before": cutoff.isoformat()})  # fmt: skip
    delete_after_commit(db_session, objects)
    return RetentionReport(cutoff=cutoff, per_patient=per_patient, objects=objects)
