"""api_token.expires_at and api_token.parent_id: tokens expire, and a token made with a token dies with it

Revision ID: 0009
Revises: 0008
Create Date: 2026-11-25 09:00:00

Tokens made before this revision never expired; they are given the default lifetime (90 days) from the day of the
upgrade, so no client stops working at once and none keeps a token for ever.
"""

import datetime as dt
from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0009"
down_revision: str | None = "0008"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

DEFAULT_DAYS = 90  # backend.users.schemas.TOKEN_DEFAULT_DAYS at the time of this migration


def upgrade() -> None:
    with op.batch_alter_table("api_token", schema=None) as batch_op:
        batch_op.add_column(sa.Column("expires_at", sa.DateTime(timezone=True), nullable=True))
        batch_op.add_column(sa.Column("parent_id", sa.Integer(), nullable=True))
        batch_op.create_index(batch_op.f("ix_api_token_parent_id"), ["parent_id"], unique=False)
        batch_op.create_foreign_key(
            batch_op.f("fk_api_token_parent_id_api_token"), "api_token", ["parent_id"], ["id"], ondelete="CASCADE"
        )
    token = sa.table("api_token", sa.column("expires_at", sa.DateTime))
    expires = dt.datetime.now(dt.UTC) + dt.timedelta(days=DEFAULT_DAYS)
    op.get_bind().execute(sa.update(token).values(expires_at=expires))
    with op.batch_alter_table("api_token", schema=None) as batch_op:
        batch_op.alter_column("expires_at", existing_type=sa.DateTime(timezone=True), nullable=False)


def downgrade() -> None:
    with op.batch_alter_table("api_token", schema=None) as batch_op:
        batch_op.drop_constraint(batch_op.f("fk_api_token_parent_id_api_token"), type_="foreignkey")
        batch_op.drop_index(batch_op.f("ix_api_token_parent_id"))
        batch_op.drop_column("parent_id")
        batch_op.drop_column("expires_at")
