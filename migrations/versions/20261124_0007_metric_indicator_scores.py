"""session_metric.indicator_scores: the four indicator scores of a session, copied out of its metrics document

Revision ID: 0007
Revises: 0006
Create Date: 2026-11-24 02:55:00

The dashboard ranks patients on the trend of their indicators over six weeks; reading them out of the whole
metrics documents (about 4.5 KB of JSON each) cost over 100 ms of database time per dashboard request. The scores
are copied at ingest (backend.sessions.metrics.scalar_columns) and backfilled here from the stored documents.
"""

import json
from collections.abc import Sequence
from typing import Any

import sqlalchemy as sa
from alembic import op

revision: str = "0007"
down_revision: str | None = "0006"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

BATCH = 500


def upgrade() -> None:
    with op.batch_alter_table("session_metric", schema=None) as batch_op:
        batch_op.add_column(sa.Column("indicator_scores", sa.JSON(), nullable=True))
    metric = sa.table("session_metric", sa.column("id", sa.Integer), sa.column("document", sa.JSON),
                      sa.column("indicator_scores", sa.JSON))  # fmt: skip
    conn = op.get_bind()
    last = 0
    while True:
        rows = conn.execute(
            sa.select(metric.c.id, metric.c.document).where(metric.c.id > last).order_by(metric.c.id).limit(BATCH)
        ).all()
        if not rows:
            break
        for row_id, document in rows:
            scores = _scores(document if isinstance(document, dict) else json.loads(document or "null"))
            if scores is not None:
                conn.execute(sa.update(metric).where(metric.c.id == row_id).values(indicator_scores=scores))
        last = rows[-1][0]


def _scores(document: Any) -> dict[str, Any] | None:
    """The same copy as backend.sessions.metrics.indicator_scores at the time of this migration."""
    indicators = document.get("indicators") if isinstance(document, dict) else None
    if not isinstance(indicators, dict):
        return None
    out = {}
    for name, value in indicators.items():
        score = value.get("score") if isinstance(value, dict) else None
        out[name] = float(score) if isinstance(score, int | float) and not isinstance(score, bool) else None
    return out


def downgrade() -> None:
    with op.batch_alter_table("session_metric", schema=None) as batch_op:
        batch_op.drop_column("indicator_scores")
