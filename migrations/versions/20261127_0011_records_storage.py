"""Session files and replays move to the object store: exercise_session.file_key, session_replay.data_key/data_hash

The upgrade writes every stored file and replay to the configured store (COACH_STORAGE_BACKEND, backend/storage) in
batches with progress and clears the blobs; with COACH_STORAGE_DEFER_MOVE=1 it only adds the columns and
`coach-server storage move-out` moves the blobs later, committing each batch (resumable; for large databases). The
downgrade brings every object back into its row first (objects stay in the store).

Revision ID: 0011_records_storage
Revises: 0010
Create Date: 2026-11-27 01:50:00
"""

import logging
import os
from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0011_records_storage"
down_revision: str | None = "0011_lang_user_locale"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

log = logging.getLogger("alembic.runtime.migration")


def upgrade() -> None:
    with op.batch_alter_table("exercise_session", schema=None) as batch_op:
        batch_op.add_column(sa.Column("file_key", sa.String(length=100), nullable=True))
    with op.batch_alter_table("session_replay", schema=None) as batch_op:
        batch_op.add_column(sa.Column("data_key", sa.String(length=100), nullable=True))
        batch_op.add_column(sa.Column("data_hash", sa.String(length=64), nullable=True))
        batch_op.alter_column("data", existing_type=sa.LargeBinary(), nullable=True)
    if os.environ.get("COACH_STORAGE_DEFER_MOVE") == "1":
        log.info("COACH_STORAGE_DEFER_MOVE=1: blobs stay; run `coach-server storage move-out`")
        return
    from backend.storage import get_store
    from backend.storage.move import move_out

    report = move_out(op.get_bind(), get_store(), progress=log.info)
    log.info("moved to %s: %s", get_store().describe(), report.text())


def downgrade() -> None:
    from backend.storage import get_store
    from backend.storage.move import move_in

    report = move_in(op.get_bind(), get_store(), progress=log.info)
    log.info("moved back from %s: %s", get_store().describe(), report.text())
    # plain ALTER TABLE … DROP COLUMN (SQLite ≥ 3.35 too): a batch table copy of exercise_session would drop the
    # table, and SQLite's ON DELETE CASCADE would take its metrics, suggestions and replays with it
    op.drop_column("exercise_session", "file_key")
    op.drop_column("session_replay", "data_key")
    op.drop_column("session_replay", "data_hash")
    if op.get_bind().dialect.name != "sqlite":  # SQLite cannot change NOT NULL in place; the models do not mind
        op.alter_column("session_replay", "data", existing_type=sa.LargeBinary(), nullable=False)
