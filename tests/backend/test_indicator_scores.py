"""session_metric.indicator_scores: the small copy of a document's indicator scores the dashboard trends read."""

from __future__ import annotations

import datetime as dt
import uuid

import sqlalchemy as sa

from backend.migrate import upgrade
from backend.sessions.metrics import indicator_scores, scalar_columns
from kinect_agent.analysis.document import read_document
from tests.backend.session_rows import document

DOC = {
    "repetitions": 8,
    "rom_deg": 71.5,
    "quality": {"ok": True},
    "indicators": {
        "flexibility": {"score": 62.0, "value": 71.5},
        "balance": {"score": None, "reason": "seated"},
        "strength": {"score": 40},
    },  # fmt: skip
}


def test_scores_are_copied_from_the_document():
    assert indicator_scores(DOC) == {"flexibility": 62.0, "balance": None, "strength": 40.0}
    assert indicator_scores({"repetitions": 3}) is None
    assert indicator_scores({"indicators": {"flexibility": "high", "endurance": {"score": True}}}) == {
        "flexibility": None,
        "endurance": None,
    }


def test_scalar_columns_are_read_from_the_model() -> None:
    doc = read_document(document(reps=8, rom=71.5, quality_ok=False))
    assert scalar_columns(doc) == {
        "repetitions": 8,
        "rom_deg": 71.5,
        "quality_ok": False,
        "indicator_scores": {"flexibility": 35.75, "endurance": None, "strength": None, "balance": None},
    }


def test_migration_0007_backfills_the_stored_documents(fresh_engine):
    now = dt.datetime(2026, 11, 20, tzinfo=dt.UTC)
    user = sa.table("user", *(sa.column(c) for c in ("id", "email", "full_name", "role", "is_active", "created_at")))
    session = sa.table("exercise_session", sa.column("id"), sa.column("client_session_id", sa.Uuid),
                       *(sa.column(c) for c in ("patient_id", "started_at", "duration_s", "n_frames", "file_bytes",
                                                "file_size", "content_hash", "processing_version", "status",
                                                "created_at")),
                       sa.column("processing_params", sa.JSON))  # fmt: skip
    metric = sa.table("session_metric", sa.column("id"), sa.column("session_id"), sa.column("document", sa.JSON),
                      sa.column("created_at"))  # fmt: skip
    with fresh_engine.begin() as conn:
        upgrade(conn, "0006")
        conn.execute(sa.insert(user).values(id=1, email="p@x.org", full_name="P", role="patient", is_active=True,
                                            created_at=now))  # fmt: skip
        for sid, doc in ((1, DOC), (2, {"repetitions": 1})):
            conn.execute(sa.insert(session).values(id=sid, client_session_id=uuid.uuid4(), patient_id=1, started_at=now,
                                                   duration_s=1.0, n_frames=30, file_bytes=b"khs", file_size=3,
                                                   content_hash="0" * 64, processing_version="", status="processed",
                                                   created_at=now, processing_params={}))  # fmt: skip
            conn.execute(sa.insert(metric).values(id=sid, session_id=sid, document=doc, created_at=now))
    with fresh_engine.begin() as conn:
        upgrade(conn, "head")
        scores = sa.table("session_metric", sa.column("id"), sa.column("indicator_scores", sa.JSON))
        rows = dict(conn.execute(sa.select(scores.c.id, scores.c.indicator_scores).order_by(scores.c.id)).all())
    assert rows == {1: {"flexibility": 62.0, "balance": None, "strength": 40.0}, 2: None}
