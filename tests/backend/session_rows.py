"""Stored sessions for server tests, written straight to the database (no upload, no analysis)."""

from __future__ import annotations

import json
import uuid
from pathlib import Path
from typing import Any

from backend.sessions.metrics import indicator_scores
from backend.sessions.models import ExerciseSession, SessionMetric
from kinect_agent.analysis.document import AnalysisReport, read_report


def store_session(
    db_session,
    patient,
    exercise,
    started_at,
    *,
    reps=10,
    rom=90.0,
    data=b"khs-bytes",
    doc=None,
    metrics=True,
    quality_ok=True,
) -> ExerciseSession:
    """Stores one session (and, with metrics=True, its metrics document) and returns it (flushed)."""
    row = ExerciseSession(
        client_session_id=uuid.uuid4(),
        patient_id=patient.id,
        exercise_id=exercise.id,
        started_at=started_at,
        duration_s=30.0,
        n_frames=900,
        file_bytes=data,
        file_size=len(data),
        content_hash="0" * 64,
        file_format="khs",
    )
    db_session.add(row)
    db_session.flush()
    if metrics:
        doc = doc or document(reps=reps, rom=rom, quality_ok=quality_ok, exercise=exercise.slug)
        db_session.add(
            SessionMetric(
                session_id=row.id,
                document=doc,
                repetitions=reps,
                rom_deg=rom,
                quality_ok=quality_ok,
                indicator_scores=indicator_scores(doc),
            )  # fmt: skip
        )
        db_session.flush()
    return row


TODAY = Path(__file__).parents[1] / "kinect_agent" / "analysis" / "documents" / "schema6.json"


def document(*, reps: int, rom: float | None, quality_ok: bool, exercise: str = "shoulder_abduction") -> dict[str, Any]:
    """Returns a stored metrics document of today's schema with these numbers; its flexibility indicator scores
    rom / 2, the other indicators have no score."""
    doc = json.loads(TODAY.read_text(encoding="utf-8"))
    doc |= {"exercise": exercise, "repetitions": reps, "rom_deg": rom}
    doc["quality"] |= {"ok": quality_ok, "reasons": [] if quality_ok else [{"id": None, "text": "test: not ok"}]}
    for name, item in doc["indicators"].items():
        item["score"] = None if rom is None or name != "flexibility" else rom / 2
    doc["indicators"]["flexibility"] |= {"value": rom, "basis": {"id": None, "params": {}, "text": "test"}}
    return doc


def report(**fields) -> AnalysisReport:
    """Returns today's example document with these top-level fields replaced; `quality` (a dict) is merged into the
    example's quality. The rules' tests describe a session by the few numbers a rule reads."""
    doc = json.loads(TODAY.read_text(encoding="utf-8"))
    doc["quality"] |= fields.pop("quality", {})
    return read_report(doc | fields)
