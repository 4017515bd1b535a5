"""Session payloads and their server metrics documents, shared by the export tests."""

from __future__ import annotations

import pytest

from backend.sessions.metrics import metrics_document
from kinect_agent.analysis.document import AnalysisDocument, AnalysisReport
from kinect_agent.analysis.exercise import get_exercise
from kinect_agent.formats import session_file as sf
from kinect_agent.sources.simulator import simulate


def session(exercise: str, reps: int, seed: int) -> tuple[sf.SessionPayload, AnalysisDocument]:
    """Returns a stored-and-read session (measured raw, exact truth as filtered) and its metrics document."""
    measured, truth, _ = simulate(exercise, reps, seed=seed)
    payload = sf.SessionPayload(session_id=f"s{seed}", raw=measured, filtered=truth, created_at="2026-11-20T10:00:00Z",
                                recorded_by={"device_id": 3, "patient_id": 7})  # fmt: skip
    payload = sf.decode(sf.encode(payload))
    # a history with one earlier session gives every indicator a score
    history: list[AnalysisReport] = [metrics_document(payload, get_exercise(exercise), target_reps=None, history=[])]
    return payload, metrics_document(payload, get_exercise(exercise), target_reps=reps, history=history)


@pytest.fixture(scope="module")
def squat_session() -> tuple[sf.SessionPayload, AnalysisDocument]:
    """A 3-repetition squat and its document."""
    return session("squat", 3, seed=11)
