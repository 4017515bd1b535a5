"""patient_archive: a patient's archive built by a worker and kept in the object store

Revision ID: archivejob_0019_patient_archive
Revises: reanalyzeraw_0018_file_versions
Create Date: 2026-11-27 23:40:00

One row per patient: where their last archive is (key and sha256), what it covers (`covers`), how many sessions it
holds and how many of those are incomplete, its size, name and when it was made. The downgrade drops the table (the
objects stay in the store; `coach-server storage check` lists them as unreferenced).
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "archivejob_0019_patient_archive"
down_revision: str | None = "reanalyzeraw_0018_file_versions"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.create_table(
        "patient_archive",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("patient_id", sa.Integer(), nullable=False),
        sa.Column("covers", sa.String(length=64), nullable=False),
        sa.Column("sessions", sa.Integer(), nullable=False),
        sa.Column("incomplete", sa.Integer(), nullable=False),
        sa.Column("data_key", sa.String(length=100), nullable=False),
        sa.Column("data_hash", sa.String(length=64), nullable=False),
        sa.Column("size", sa.BigInteger(), nullable=False),
        sa.Column("file_name", sa.String(length=100), nullable=False),
        sa.Column("made_at", sa.DateTime(timezone=True), nullable=False),
        sa.ForeignKeyConstraint(["patient_id"], ["user.id"], name=op.f("fk_patient_archive_patient_id_user"),
                                ondelete="CASCADE"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_patient_archive")),
        sa.UniqueConstraint("patient_id", name=op.f("uq_patient_archive_patient_id")),
    )  # fmt: skip


def downgrade() -> None:
    op.drop_table("patient_archive")
