"""voice_preference: whether a patient's page speaks during a live set, and how loud

Revision ID: 0011_voice_preference
Revises: 0011_lang_user_locale
Create Date: 2026-11-27 02:10:00
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0011_voice_preference"
down_revision: str | None = "0012_records_jobs"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.create_table(
        "voice_preference",
        sa.Column("patient_id", sa.Integer(), nullable=False),
        sa.Column("enabled", sa.Boolean(), nullable=False),
        sa.Column("volume", sa.Double(), nullable=False),
        sa.Column("updated_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("updated_by_id", sa.Integer(), nullable=True),
        sa.ForeignKeyConstraint(
            ["patient_id"], ["user.id"], name=op.f("fk_voice_preference_patient_id_user"), ondelete="CASCADE"
        ),
        sa.ForeignKeyConstraint(
            ["updated_by_id"], ["user.id"], name=op.f("fk_voice_preference_updated_by_id_user"), ondelete="SET NULL"
        ),
        sa.PrimaryKeyConstraint("patient_id", name=op.f("pk_voice_preference")),
    )


def downgrade() -> None:
    op.drop_table("voice_preference")
