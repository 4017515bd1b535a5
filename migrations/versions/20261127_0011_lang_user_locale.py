"""user.locale: the language of a patient's pages, set by their therapist or by the patient

Revision ID: 0011_lang_user_locale
Revises: 0010
Create Date: 2026-11-27 01:40:00
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0011_lang_user_locale"
down_revision: str | None = "0011_camera_sets"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    with op.batch_alter_table("user", schema=None) as batch_op:
        batch_op.add_column(sa.Column("locale", sa.String(length=16), nullable=True))


def downgrade() -> None:
    # plain ALTER TABLE … DROP COLUMN (SQLite >= 3.35 too): a batch copy of "user" would drop the table, and SQLite's
    # ON DELETE CASCADE would take every session, metric and replay of every user with it
    op.drop_column("user", "locale")
