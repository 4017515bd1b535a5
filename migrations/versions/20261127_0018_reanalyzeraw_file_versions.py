"""session_metric_version.file_key, file_hash, processing_params: the session file a replaced document came from

A re-analysis with the pipeline (`coach-server reanalyze --pipeline`) filters a session's raw recording again and
writes a new session file; the earlier file stays in the object store, named by these columns beside the metrics it
gave. Rows replaced before this revision keep null (unknown).

Revision ID: reanalyzeraw_0018_file_versions
Revises: exports_0017_stored_export
Create Date: 2026-11-27 17:30:00

Plain add_column / drop_column. The downgrade drops the columns: earlier files that only they named stay in the
store, listed by `coach-server storage check --orphans`.
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "reanalyzeraw_0018_file_versions"
down_revision: str | None = "exports_0017_stored_export"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    op.add_column("session_metric_version", sa.Column("file_key", sa.String(length=100), nullable=True))
    op.add_column("session_metric_version", sa.Column("file_hash", sa.String(length=64), nullable=True))
    op.add_column("session_metric_version", sa.Column("processing_params", sa.JSON(), nullable=True))


def downgrade() -> None:
    op.drop_column("session_metric_version", "processing_params")
    op.drop_column("session_metric_version", "file_hash")
    op.drop_column("session_metric_version", "file_key")
