"""session_replay.layers (one skeleton alone is stored too) and session_detail (the session page's evidence, stored)

Revision ID: offrequest_0016_stored_detail
Revises: advicelang_0016_params
Create Date: 2026-11-27 07:40:00

session_replay was one row per session (both skeletons); the replay of one skeleton alone, built in the request
until now, is built by a worker and kept as a row of its own: the unique key becomes (session_id, layers), the
existing rows are both skeletons. session_detail keeps where the stored detail document is. The downgrade drops
the one-skeleton rows (their objects stay in the store; `coach-server storage check` lists them as unreferenced).
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "offrequest_0016_stored_detail"
down_revision: str | None = "advicelang_0016_params"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

BOTH = "raw,filtered"


def upgrade() -> None:
    with op.batch_alter_table("session_replay", schema=None) as batch_op:
        batch_op.add_column(sa.Column("layers", sa.String(length=20), nullable=False, server_default=BOTH))
        batch_op.drop_constraint("uq_session_replay_session_id", type_="unique")
        batch_op.create_unique_constraint("uq_session_replay_session_id_layers", ["session_id", "layers"])
    op.create_table(
        "session_detail",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("session_id", sa.Integer(), nullable=False),
        sa.Column("inputs", sa.String(length=64), nullable=False),
        sa.Column("data_key", sa.String(length=100), nullable=False),
        sa.Column("data_hash", sa.String(length=64), nullable=False),
        sa.Column("size", sa.Integer(), nullable=False),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.ForeignKeyConstraint(["session_id"], ["exercise_session.id"],
                                name=op.f("fk_session_detail_session_id_exercise_session"), ondelete="CASCADE"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_session_detail")),
        sa.UniqueConstraint("session_id", name=op.f("uq_session_detail_session_id")),
    )  # fmt: skip


def downgrade() -> None:
    op.drop_table("session_detail")
    replay = sa.table("session_replay", sa.column("layers", sa.String))
    op.execute(sa.delete(replay).where(replay.c.layers != BOTH))
    with op.batch_alter_table("session_replay", schema=None) as batch_op:
        batch_op.drop_constraint("uq_session_replay_session_id_layers", type_="unique")
        batch_op.create_unique_constraint("uq_session_replay_session_id", ["session_id"])
        batch_op.drop_column("layers")
