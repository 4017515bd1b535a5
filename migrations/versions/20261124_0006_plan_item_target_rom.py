"""plan_item.target_rom_deg: the range of motion a therapist sets as the target of one prescribed exercise

Revision ID: 0006
Revises: 0005
Create Date: 2026-11-24 09:30:00

Therapists prescribe plans from their pages now: per exercise sets, repetitions, days per week and a target range
of motion in degrees (optional; NULL: no target). The plan's notes are the note shown to the patient.
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0006"
down_revision: str | None = "0005"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    with op.batch_alter_table("plan_item", schema=None) as batch_op:
        batch_op.add_column(sa.Column("target_rom_deg", sa.Double(), nullable=True))
        batch_op.create_check_constraint(
            op.f("ck_plan_item_target_rom_range"),
            "target_rom_deg IS NULL OR (target_rom_deg > 0 AND target_rom_deg <= 180)",
        )


def downgrade() -> None:
    with op.batch_alter_table("plan_item", schema=None) as batch_op:
        batch_op.drop_constraint(op.f("ck_plan_item_target_rom_range"), type_="check")
        batch_op.drop_column("target_rom_deg")
