"""suggestion.value: the measured value a rule compared with its threshold

Revision ID: 0003
Revises: 0002
Create Date: 2026-11-23 11:40:00

A system suggestion says "value <comparison> threshold" held for its metric (e.g. repetitions 6 < 10); with the
value stored, a therapist sees the whole check without opening the session's metrics.
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0003"
down_revision: str | None = "0002"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    with op.batch_alter_table("suggestion", schema=None) as batch_op:
        batch_op.add_column(sa.Column("value", sa.Double(), nullable=True))


def downgrade() -> None:
    with op.batch_alter_table("suggestion", schema=None) as batch_op:
        batch_op.drop_column("value")
