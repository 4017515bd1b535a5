"""user.pain_alert_above: the pain (0-10) above which a patient's answer after a set raises their attention score

Revision ID: feel_pain_alert
Revises: remind_reminders
Create Date: 2026-11-27 04:40:00

Plain add_column / drop_column (no batch copy: on SQLite a batch copy of "user" would cascade deletes).
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "feel_pain_alert"
down_revision: str | None = "remind_reminders"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.add_column("user", sa.Column("pain_alert_above", sa.SmallInteger(), nullable=True))


def downgrade() -> None:
    op.drop_column("user", "pain_alert_above")
