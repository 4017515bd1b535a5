"""session_export: a session's downloads (csv, trc, bvh, fhir) built by a worker and kept in the object store

Revision ID: exports_0017_stored_export
Revises: offrequest_0016_stored_detail
Create Date: 2026-11-27 11:10:00

One row per session and format: where the file is (key and sha256), what it was made from (`inputs`), its size,
Content-Type and name. The downgrade drops the table (the objects stay in the store; `coach-server storage check`
lists them as unreferenced).
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "exports_0017_stored_export"
down_revision: str | None = "offrequest_0016_stored_detail"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.create_table(
        "session_export",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("session_id", sa.Integer(), nullable=False),
        sa.Column("format", sa.String(length=8), nullable=False),
        sa.Column("inputs", sa.String(length=64), nullable=False),
        sa.Column("data_key", sa.String(length=100), nullable=False),
        sa.Column("data_hash", sa.String(length=64), nullable=False),
        sa.Column("size", sa.Integer(), nullable=False),
        sa.Column("media_type", sa.String(length=64), nullable=False),
        sa.Column("file_name", sa.String(length=100), nullable=False),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.ForeignKeyConstraint(["session_id"], ["exercise_session.id"],
                                name=op.f("fk_session_export_session_id_exercise_session"), ondelete="CASCADE"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_session_export")),
        sa.UniqueConstraint("session_id", "format", name=op.f("uq_session_export_session_id_format")),
    )  # fmt: skip


def downgrade() -> None:
    op.drop_table("session_export")
