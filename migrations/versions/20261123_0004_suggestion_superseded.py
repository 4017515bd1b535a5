"""suggestion.status 'superseded': newer advice of the same rule and exercise replaces pending older advice

Revision ID: 0004
Revises: 0003
Create Date: 2026-11-23 12:55:00

Each session can fire the same rule again (six sessions with too few repetitions make six pending "do all 10"
suggestions); when a newer session fires a rule, the older still-pending suggestions of that rule for the same
exercise become 'superseded', so a therapist reviews the newest advice once.
"""

from collections.abc import Sequence

from alembic import op

revision: str = "0004"
down_revision: str | None = "0003"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

NEW = "status IN ('pending', 'approved', 'dismissed', 'superseded')"
OLD = "status IN ('pending', 'approved', 'dismissed')"


def upgrade() -> None:
    with op.batch_alter_table("suggestion", schema=None) as batch_op:
        batch_op.drop_constraint(batch_op.f("ck_suggestion_status"), type_="check")
        batch_op.create_check_constraint(batch_op.f("ck_suggestion_status"), NEW)


def downgrade() -> None:
    op.execute("UPDATE suggestion SET status = 'dismissed' WHERE status = 'superseded'")
    with op.batch_alter_table("suggestion", schema=None) as batch_op:
        batch_op.drop_constraint(batch_op.f("ck_suggestion_status"), type_="check")
        batch_op.create_check_constraint(batch_op.f("ck_suggestion_status"), OLD)
