"""advice_reply: the patient's replies to advice (a preset, a few words, or both), unread until a therapist reads them

Revision ID: msgs_0015_advice_reply
Revises: 0014_harden_live_set
Create Date: 2026-11-27 04:40:00
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "msgs_0015_advice_reply"
down_revision: str | None = "0014_harden_live_set"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.create_table(
        "advice_reply",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("suggestion_id", sa.Integer(), nullable=False),
        sa.Column("patient_id", sa.Integer(), nullable=False),
        sa.Column("preset", sa.String(length=16), nullable=True),
        sa.Column("text", sa.String(length=500), nullable=True),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("read_at", sa.DateTime(timezone=True), nullable=True),
        sa.Column("read_by_id", sa.Integer(), nullable=True),
        sa.CheckConstraint("preset IN ('done', 'hurt', 'call_me')", name=op.f("ck_advice_reply_preset")),
        sa.CheckConstraint("preset IS NOT NULL OR text IS NOT NULL", name=op.f("ck_advice_reply_says_something")),
        sa.ForeignKeyConstraint(
            ["suggestion_id"],
            ["suggestion.id"],
            name=op.f("fk_advice_reply_suggestion_id_suggestion"),
            ondelete="CASCADE",
        ),
        sa.ForeignKeyConstraint(
            ["patient_id"], ["user.id"], name=op.f("fk_advice_reply_patient_id_user"), ondelete="CASCADE"
        ),
        sa.ForeignKeyConstraint(
            ["read_by_id"], ["user.id"], name=op.f("fk_advice_reply_read_by_id_user"), ondelete="SET NULL"
        ),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_advice_reply")),
    )
    op.create_index(op.f("ix_advice_reply_suggestion_id"), "advice_reply", ["suggestion_id"])
    op.create_index("ix_advice_reply_patient_id_read_at", "advice_reply", ["patient_id", "read_at"])


def downgrade() -> None:
    op.drop_index("ix_advice_reply_patient_id_read_at", table_name="advice_reply")
    op.drop_index(op.f("ix_advice_reply_suggestion_id"), table_name="advice_reply")
    op.drop_table("advice_reply")
