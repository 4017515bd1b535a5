"""session_feeling: pain (0-10) and effort (Borg CR10) the patient gives after a set

Revision ID: 0011_voice_session_feeling
Revises: 0011_voice_preference
Create Date: 2026-11-27 02:30:00
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0011_voice_session_feeling"
down_revision: str | None = "0011_voice_preference"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.create_table(
        "session_feeling",
        sa.Column("session_id", sa.Integer(), nullable=False),
        sa.Column("pain_nrs", sa.Integer(), nullable=True),
        sa.Column("effort_cr10", sa.Double(), nullable=True),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("updated_at", sa.DateTime(timezone=True), nullable=False),
        sa.ForeignKeyConstraint(
            ["session_id"],
            ["exercise_session.id"],
            name=op.f("fk_session_feeling_session_id_exercise_session"),
            ondelete="CASCADE",
        ),
        sa.PrimaryKeyConstraint("session_id", name=op.f("pk_session_feeling")),
    )


def downgrade() -> None:
    op.drop_table("session_feeling")
