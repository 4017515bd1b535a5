"""reminders: plan.reminder_times, user.time_zone and user.reminder_emails_off_at, table reminder_sent

Revision ID: remind_reminders
Revises: msgs_0015_advice_reply
Create Date: 2026-11-27 04:40:00

Plain add_column / drop_column (no batch copy: on SQLite a batch copy of `user` or `plan` would cascade deletes).
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "remind_reminders"
down_revision: str | None = "msgs_0015_advice_reply"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.add_column("plan", sa.Column("reminder_times", sa.JSON(), nullable=False, server_default="[]"))
    op.add_column("user", sa.Column("time_zone", sa.String(length=64), nullable=True))
    op.add_column("user", sa.Column("reminder_emails_off_at", sa.DateTime(timezone=True), nullable=True))
    op.create_table(
        "reminder_sent",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("plan_id", sa.Integer(), nullable=False),
        sa.Column("patient_id", sa.Integer(), nullable=False),
        sa.Column("local_date", sa.Date(), nullable=False),
        sa.Column("local_time", sa.String(length=5), nullable=False),
        sa.Column("due_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("token_hash", sa.String(length=64), nullable=False),
        sa.Column("claimed_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("sent_at", sa.DateTime(timezone=True), nullable=True),
        sa.Column("error", sa.Text(), nullable=True),
        sa.ForeignKeyConstraint(
            ["plan_id"], ["plan.id"], name=op.f("fk_reminder_sent_plan_id_plan"), ondelete="CASCADE"
        ),
        sa.ForeignKeyConstraint(
            ["patient_id"], ["user.id"], name=op.f("fk_reminder_sent_patient_id_user"), ondelete="CASCADE"
        ),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_reminder_sent")),
        sa.UniqueConstraint(
            "plan_id", "local_date", "local_time", name=op.f("uq_reminder_sent_plan_id_local_date_local_time")
        ),
        sa.UniqueConstraint("token_hash", name=op.f("uq_reminder_sent_token_hash")),
    )
    op.create_index(op.f("ix_reminder_sent_patient_id"), "reminder_sent", ["patient_id"], unique=False)


def downgrade() -> None:
    op.drop_index(op.f("ix_reminder_sent_patient_id"), table_name="reminder_sent")
    op.drop_table("reminder_sent")
    op.drop_column("user", "reminder_emails_off_at")
    op.drop_column("user", "time_zone")
    op.drop_column("plan", "reminder_times")
