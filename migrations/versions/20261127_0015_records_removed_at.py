"""exercise_session.file_removed_at: when the retention period removed the session's file (its tombstone)

Revision ID: records_0015_removed_at
Revises: feel_pain_alert
Create Date: 2026-11-27 04:40:00

Sessions whose files a retention run removed before this column existed get the time of that run, read from its
audit row ("session.files_expired": the patient and the cut-off). Plain add_column / drop_column (no batch copy:
on SQLite a batch copy of `exercise_session` would cascade deletes).
"""

import datetime as dt
import json
from collections.abc import Sequence
from typing import Any

import sqlalchemy as sa
from alembic import op

revision: str = "records_0015_removed_at"
down_revision: str | None = "feel_pain_alert"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def _started_before(detail: Any, dialect: str) -> dt.datetime | None:
    """Returns the cut-off of a retention audit row's detail (a dict, or its JSON text on some drivers) as the
    dialect stores times: UTC, naive on SQLite (backend.database.UTCDateTime)."""
    if isinstance(detail, str):
        detail = json.loads(detail)
    text = (detail or {}).get("started_before")
    if not text:
        return None
    cutoff = dt.datetime.fromisoformat(text)
    cutoff = cutoff.replace(tzinfo=dt.UTC) if cutoff.tzinfo is None else cutoff.astimezone(dt.UTC)
    return cutoff.replace(tzinfo=None) if dialect == "sqlite" else cutoff


def upgrade() -> None:
    op.add_column("exercise_session", sa.Column("file_removed_at", sa.DateTime(timezone=True), nullable=True))
    session = sa.table(
        "exercise_session",
        sa.column("patient_id", sa.Integer),
        sa.column("started_at", sa.DateTime),
        sa.column("file_key", sa.String),
        sa.column("file_bytes", sa.LargeBinary),
        sa.column("file_removed_at", sa.DateTime),
    )
    audit = sa.table(
        "audit_event", sa.column("action", sa.String), sa.column("patient_id", sa.Integer),
        sa.column("detail", sa.JSON), sa.column("at", sa.DateTime),
    )  # fmt: skip
    bind = op.get_bind()
    runs = bind.execute(
        sa.select(audit.c.patient_id, audit.c.detail, audit.c.at)
        .where(audit.c.action == "session.files_expired")
        .order_by(audit.c.at)
    ).all()
    for patient_id, detail, created_at in runs:  # oldest run first: a session gets the run that removed it
        cutoff = _started_before(detail, bind.dialect.name)
        if cutoff is None or patient_id is None:
            continue
        bind.execute(
            sa.update(session)
            .where(session.c.patient_id == patient_id, session.c.started_at < cutoff,
                   session.c.file_key.is_(None), session.c.file_bytes.is_(None),
                   session.c.file_removed_at.is_(None))
            .values(file_removed_at=created_at)
        )  # fmt: skip


def downgrade() -> None:
    op.drop_column("exercise_session", "file_removed_at")
