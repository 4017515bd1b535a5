"""index exercise_session (patient_id, started_at, id) for the dashboard reads

Revision ID: 0002
Revises: 0001
Create Date: 2026-11-23 11:20:00

The therapist dashboard asks, per patient, for the newest session (ORDER BY started_at DESC, id DESC LIMIT 1),
this week's sessions (started_at >= Monday) and one patient's sessions newest first; this index answers each
with a short backward index scan instead of reading and sorting all of the patient's sessions.
"""

from collections.abc import Sequence

from alembic import op

revision: str = "0002"
down_revision: str | None = "0001"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

INDEX = "ix_exercise_session_patient_id_started_at"


def upgrade() -> None:
    with op.batch_alter_table("exercise_session", schema=None) as batch_op:
        batch_op.create_index(INDEX, ["patient_id", "started_at", "id"], unique=False)


def downgrade() -> None:
    with op.batch_alter_table("exercise_session", schema=None) as batch_op:
        batch_op.drop_index(INDEX)
