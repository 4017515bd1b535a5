"""camera_consent, camera_set, camera_batch: sets a patient records with the browser's own camera

Revision ID: 0011_camera_sets
Revises: 0010
Create Date: 2026-11-27 01:40:00

The page sends landmarks only (never images) in numbered batches; the set's end stores a normal session
(backend/camera, docs/camera-sets.md).
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0011_camera_sets"
down_revision: str | None = "0010"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.create_table(
        "camera_consent",
        sa.Column("patient_id", sa.Integer(), nullable=False),
        sa.Column("consent_version", sa.String(length=16), nullable=False),
        sa.Column("given_at", sa.DateTime(timezone=True), nullable=False),
        sa.ForeignKeyConstraint(
            ["patient_id"], ["user.id"], name=op.f("fk_camera_consent_patient_id_user"), ondelete="CASCADE"
        ),
        sa.PrimaryKeyConstraint("patient_id", name=op.f("pk_camera_consent")),
    )
    op.create_table(
        "camera_set",
        sa.Column("id", sa.Uuid(), nullable=False),
        sa.Column("patient_id", sa.Integer(), nullable=False),
        sa.Column("plan_item_id", sa.Integer(), nullable=True),
        sa.Column("exercise_id", sa.Integer(), nullable=False),
        sa.Column("target_reps", sa.Integer(), nullable=False),
        sa.Column("model_name", sa.String(length=64), nullable=False),
        sa.Column("status", sa.String(length=16), nullable=False),
        sa.Column("n_frames", sa.Integer(), nullable=False),
        sa.Column("n_batches", sa.Integer(), nullable=False),
        sa.Column("last_seq", sa.Integer(), nullable=False),
        sa.Column("last_t", sa.Double(), nullable=True),
        sa.Column("started_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("ended_at", sa.DateTime(timezone=True), nullable=True),
        sa.Column("end_reason", sa.String(length=16), nullable=True),
        sa.Column("session_id", sa.Integer(), nullable=True),
        sa.Column("error", sa.Text(), nullable=True),
        sa.ForeignKeyConstraint(
            ["exercise_id"], ["exercise.id"], name=op.f("fk_camera_set_exercise_id_exercise"), ondelete="RESTRICT"
        ),
        sa.ForeignKeyConstraint(
            ["patient_id"], ["user.id"], name=op.f("fk_camera_set_patient_id_user"), ondelete="CASCADE"
        ),
        sa.ForeignKeyConstraint(
            ["plan_item_id"], ["plan_item.id"], name=op.f("fk_camera_set_plan_item_id_plan_item"), ondelete="SET NULL"
        ),
        sa.ForeignKeyConstraint(
            ["session_id"],
            ["exercise_session.id"],
            name=op.f("fk_camera_set_session_id_exercise_session"),
            ondelete="SET NULL",
        ),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_camera_set")),
    )
    with op.batch_alter_table("camera_set", schema=None) as batch_op:
        batch_op.create_index(batch_op.f("ix_camera_set_exercise_id"), ["exercise_id"], unique=False)
        batch_op.create_index(batch_op.f("ix_camera_set_patient_id"), ["patient_id"], unique=False)
        batch_op.create_index(batch_op.f("ix_camera_set_plan_item_id"), ["plan_item_id"], unique=False)
    op.create_table(
        "camera_batch",
        sa.Column("id", sa.Integer(), nullable=False),
        sa.Column("set_id", sa.Uuid(), nullable=False),
        sa.Column("seq", sa.Integer(), nullable=False),
        sa.Column("n_frames", sa.Integer(), nullable=False),
        sa.Column("t_first", sa.Double(), nullable=False),
        sa.Column("t_last", sa.Double(), nullable=False),
        sa.Column("image_width", sa.Integer(), nullable=False),
        sa.Column("image_height", sa.Integer(), nullable=False),
        sa.Column("content_hash", sa.String(length=64), nullable=False),
        sa.Column("data", sa.LargeBinary(), nullable=False),
        sa.Column("received_at", sa.DateTime(timezone=True), nullable=False),
        sa.ForeignKeyConstraint(
            ["set_id"], ["camera_set.id"], name=op.f("fk_camera_batch_set_id_camera_set"), ondelete="CASCADE"
        ),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_camera_batch")),
        sa.UniqueConstraint("set_id", "seq", name=op.f("uq_camera_batch_set_id_seq")),
    )
    with op.batch_alter_table("camera_batch", schema=None) as batch_op:
        batch_op.create_index(batch_op.f("ix_camera_batch_set_id"), ["set_id"], unique=False)


def downgrade() -> None:
    op.drop_table("camera_batch")
    with op.batch_alter_table("camera_set", schema=None) as batch_op:
        batch_op.drop_index(batch_op.f("ix_camera_set_plan_item_id"))
        batch_op.drop_index(batch_op.f("ix_camera_set_patient_id"))
        batch_op.drop_index(batch_op.f("ix_camera_set_exercise_id"))
    op.drop_table("camera_set")
    op.drop_table("camera_consent")
