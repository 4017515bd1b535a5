"""device.live_set_id: the last set the server started on a home agent; live progress is accepted only for it

Revision ID: 0014_harden_live_set
Revises: 0011_voice_session_feeling
Create Date: 2026-11-27 03:20:00

Plain add_column / drop_column (no batch copy: on SQLite a batch copy of `device` would cascade deletes).
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0014_harden_live_set"
down_revision: str | None = "0011_voice_session_feeling"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.add_column("device", sa.Column("live_set_id", sa.String(length=36), nullable=True))


def downgrade() -> None:
    op.drop_column("device", "live_set_id")
