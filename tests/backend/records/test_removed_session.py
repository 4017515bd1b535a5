"""A session whose recording the retention period removed: a tombstone with the date, 410 SessionFileRemoved in
words from every route that needs the recording, its metadata and metrics still readable."""

from __future__ import annotations

import datetime as dt

import pytest
import sqlalchemy as sa

from backend.records.retention import apply_retention
from backend.sessions.models import ExerciseSession
from tests.backend.khs_files import make_khs

NOW = dt.datetime(2026, 11, 27, 3, 30, tzinfo=dt.UTC)
SENTENCE = "This session was removed on 2026-11-27 under the clinic's retention policy"


def _removed_session(client, db_session, make_patient_with_therapist, auth_headers, seed: int):
    """Returns (session id, patient, therapist) of an uploaded squat whose file a 365-day retention removed on NOW."""
    patient, therapist = make_patient_with_therapist()
    response = client.post("/api/v1/sessions", content=make_khs("squat", 1, seed=seed),
                           headers={"Content-Type": "application/octet-stream", **auth_headers(patient)},
                           params={"exercise": "squat"})  # fmt: skip
    assert response.status_code == 201, response.text
    session_id = response.json()["id"]
    db_session.get(ExerciseSession, session_id).started_at = dt.datetime(2025, 1, 1, tzinfo=dt.UTC)
    db_session.flush()
    apply_retention(db_session=db_session, days=365, now=NOW)
    db_session.commit()
    return session_id, patient, therapist


def test_retention_leaves_a_tombstone_with_the_date(client, db_session, make_patient_with_therapist, auth_headers,
                                                     with_store):  # fmt: skip
    session_id, patient, therapist = _removed_session(client, db_session, make_patient_with_therapist, auth_headers, 91)
    db_session.expire_all()
    row = db_session.get(ExerciseSession, session_id)
    assert row.file_key is None and row.file_removed_at == NOW
    body = client.get(f"/api/v1/sessions/{session_id}", headers=auth_headers(therapist)).json()
    assert body["file_removed_at"].startswith("2026-11-27T03:30") and body["repetitions"] is not None
    assert body["metrics"]["rom_deg"] is not None, "the metrics stay"


@pytest.mark.parametrize("route", ["detail", "replay", "replay/state", "export?format=csv", "file"])
def test_routes_that_need_the_recording_answer_410_in_words(route, client, db_session, make_patient_with_therapist,
                                                            auth_headers, with_store):  # fmt: skip
    session_id, _, therapist = _removed_session(client, db_session, make_patient_with_therapist, auth_headers, 92)
    response = client.get(f"/api/v1/sessions/{session_id}/{route}", headers=auth_headers(therapist))
    assert response.status_code == 410, response.text
    body = response.json()
    assert set(body) == {"error", "detail"} and body["error"] == "SessionFileRemoved"
    assert body["detail"].startswith(SENTENCE), body["detail"]
    assert "its metrics are kept" in body["detail"]


def test_a_stranger_still_gets_404_not_the_tombstone(client, db_session, make_patient_with_therapist, make_user,
                                                      auth_headers, with_store):  # fmt: skip
    stranger_headers = auth_headers(make_user("patient"))
    session_id, _, _ = _removed_session(client, db_session, make_patient_with_therapist, auth_headers, 93)
    response = client.get(f"/api/v1/sessions/{session_id}/detail", headers=stranger_headers)
    assert response.status_code == 404 and response.json()["error"] == "SessionNotFound"


def test_the_removed_sessions_route_errors_are_documented(client):
    paths = client.get("/openapi.json").json()["paths"]
    for route in ("detail", "replay", "export", "file"):
        answers = paths[f"/api/v1/sessions/{{session_id}}/{route}"]["get"]["responses"]
        assert "SessionFileRemoved" in answers["410"]["description"], route


def test_old_rows_without_a_date_still_answer_in_words(client, db_session, make_patient_with_therapist, auth_headers,
                                                       with_store):  # fmt: skip
    session_id, _, therapist = _removed_session(client, db_session, make_patient_with_therapist, auth_headers, 94)
    db_session.execute(sa.update(ExerciseSession).where(ExerciseSession.id == session_id).values(file_removed_at=None))
    db_session.commit()
    response = client.get(f"/api/v1/sessions/{session_id}/detail", headers=auth_headers(therapist))
    assert response.status_code == 410
    assert response.json()["detail"].startswith("This session was removed under the clinic's retention policy")
