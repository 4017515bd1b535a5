"""An internal fault of the signal processing during an upload: 500 with the fault named, logged with the request and
the session, nothing stored (the agent keeps its file and retries); never a 4xx that blames the file."""

from __future__ import annotations

import logging

from sqlalchemy import func, select

from backend.sessions.models import ExerciseSession
from kinect_agent.processing.errors import NotPositiveDefinite
from tests.backend.khs_files import make_khs


def test_a_processing_fault_answers_500_logged_with_context(client, db_session, make_user, device_headers,
                                                            monkeypatch, caplog):  # fmt: skip
    patient = make_user("patient")
    _, headers = device_headers(patient)
    db_session.commit()

    def faulty_analysis(*_args, **_kwargs):
        raise NotPositiveDefinite("innovation covariance S (6, 6)", 5)

    monkeypatch.setattr("backend.sessions.service.metrics_document", faulty_analysis)
    with caplog.at_level(logging.ERROR, logger="backend.main"):
        response = client.post("/api/v1/sessions", content=make_khs("squat", 2, seed=3),
                               headers={"Content-Type": "application/octet-stream", **headers})  # fmt: skip
    assert response.status_code == 500, response.text
    body = response.json()
    assert body["error"] == "NotPositiveDefinite"
    assert "internal fault" in body["detail"] and "not positive definite" in body["detail"]
    record = next(r for r in caplog.records if "internal fault of the signal processing" in r.getMessage())
    assert "POST /api/v1/sessions" in record.getMessage()
    notes = getattr(record.exc_info[1], "__notes__", [])
    assert any(f"of patient {patient.id} (squat)" in note for note in notes), notes
    db_session.expire_all()
    stored = db_session.scalar(
        select(func.count()).select_from(ExerciseSession).where(ExerciseSession.patient_id == patient.id)
    )
    assert stored == 0, "nothing is stored when the analysis fails inside"
