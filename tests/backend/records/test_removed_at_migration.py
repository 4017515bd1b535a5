"""Migration records_0015: sessions whose files a retention run removed before the tombstone column existed get
the time of that run, from its audit row; kept files and other patients' sessions get none."""

from __future__ import annotations

import datetime as dt
import uuid

import sqlalchemy as sa

from backend.migrate import downgrade, upgrade

RUN = dt.datetime(2026, 11, 26, 2, 0, tzinfo=dt.UTC)
OLD, NEW = dt.datetime(2025, 1, 1, tzinfo=dt.UTC), dt.datetime(2026, 11, 1, tzinfo=dt.UTC)
USER = sa.table("user", *(sa.column(c) for c in ("id", "email", "full_name", "role", "is_active", "created_at")))
SESSION = sa.table("exercise_session", sa.column("id"), sa.column("client_session_id", sa.Uuid),
                   *(sa.column(c) for c in ("patient_id", "started_at", "duration_s", "n_frames", "file_key",
                                            "file_size", "content_hash", "processing_version", "status", "created_at")),
                   sa.column("processing_params", sa.JSON))  # fmt: skip
AUDIT = sa.table("audit_event", *(sa.column(c) for c in ("id", "at", "action", "object_type", "object_id",
                                                         "patient_id")), sa.column("detail", sa.JSON))  # fmt: skip


def _as_stored(when: dt.datetime, dialect: str) -> dt.datetime:
    return when.replace(tzinfo=None) if dialect == "sqlite" else when


def test_upgrade_dates_the_files_an_earlier_retention_run_removed(fresh_engine):
    dialect = fresh_engine.dialect.name
    with fresh_engine.begin() as conn:
        upgrade(conn, "0014_harden_live_set")
        for uid in (1, 2):
            conn.execute(sa.insert(USER).values(id=uid, email=f"p{uid}@x.org", full_name="P", role="patient",
                                                is_active=True, created_at=_as_stored(OLD, dialect)))  # fmt: skip
        rows = {1: (1, OLD, None), 2: (1, NEW, "session/ab/kept"), 3: (2, OLD, None), 4: (1, NEW, None)}
        for sid, (pid, started, key) in rows.items():
            conn.execute(sa.insert(SESSION).values(id=sid, client_session_id=uuid.uuid4(), patient_id=pid,
                                                   started_at=_as_stored(started, dialect), duration_s=1.0,
                                                   n_frames=30, file_key=key, file_size=1, content_hash="0" * 64,
                                                   processing_version="", status="processed",
                                                   created_at=_as_stored(started, dialect),
                                                   processing_params={}))  # fmt: skip
        cutoff = RUN - dt.timedelta(days=365)
        conn.execute(sa.insert(AUDIT).values(id=1, at=_as_stored(RUN, dialect), action="session.files_expired",
                                             object_type="patient", object_id="1", patient_id=1,
                                             detail={"files": 1, "retention_days": 365,
                                                     "started_before": cutoff.isoformat()}))  # fmt: skip
        upgrade(conn, "head")
    with fresh_engine.connect() as conn:
        got = dict(conn.execute(sa.text("SELECT id, file_removed_at FROM exercise_session ORDER BY id")).all())
    removed = dt.datetime.fromisoformat(got[1]) if isinstance(got[1], str) else got[1]  # SQLite: text
    removed = removed.replace(tzinfo=dt.UTC) if removed is not None and removed.tzinfo is None else removed
    assert removed == RUN, got
    assert got[2] is None, "a kept file has no tombstone"
    assert got[3] is None, "the run was about patient 1 only"
    assert got[4] is None, "started after the run's cut-off"
    with fresh_engine.begin() as conn:
        downgrade(conn, "0014_harden_live_set")
    with fresh_engine.connect() as conn:
        assert "file_removed_at" not in {c["name"] for c in sa.inspect(conn).get_columns("exercise_session")}
