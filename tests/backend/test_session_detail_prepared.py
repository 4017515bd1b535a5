"""GET /sessions/{id}/detail is prepared by a worker and stored, never computed in the request: 202 while it builds,
then the stored document; a re-analysis makes it stale; a file that cannot be shown is said once, not retried."""

from __future__ import annotations

import datetime as dt
import json

from sqlalchemy import func, select

from backend.jobs.models import Job
from backend.sessions.models import ExerciseSession, SessionDetail, SessionMetric
from backend.storage import get_store
from tests.backend.khs_files import make_khs

T0 = dt.datetime(2026, 11, 2, 9, 0, tzinfo=dt.UTC)


def _post(client, patient, auth_headers, data: bytes, exercise: str = "squat") -> int:
    headers = {"Content-Type": "application/octet-stream", **auth_headers(patient)}
    response = client.post("/api/v1/sessions", content=data, headers=headers, params={"exercise": exercise})
    assert response.status_code == 201, response.text
    return response.json()["id"]


def test_an_upload_queues_the_detail_and_the_request_reads_what_a_worker_stored(
    client, make_patient_with_therapist, auth_headers, db_session, run_jobs
):
    patient, therapist = make_patient_with_therapist()
    session_id = _post(client, patient, auth_headers, make_khs("squat", 3, seed=31))
    th = auth_headers(therapist)
    assert db_session.scalar(select(Job.key).where(Job.kind == "detail")).startswith(f"detail:{session_id}:")
    first = client.get(f"/api/v1/sessions/{session_id}/detail", headers=th)
    assert first.status_code == 202 and first.headers["retry-after"] == "2", first.text
    assert first.json()["state"] == "preparing" and "queued" in first.json()["detail"]
    assert db_session.scalar(select(func.count()).select_from(SessionDetail)) == 0, "nothing built in a request"
    assert db_session.scalar(select(func.count()).select_from(Job).where(Job.kind == "detail")) == 1, "queued once"
    assert run_jobs() == 1
    ready = client.get(f"/api/v1/sessions/{session_id}/detail", headers=th)
    assert ready.status_code == 200, ready.text
    body = ready.json()
    assert body["session_id"] == session_id and body["patient_id"] == patient.id and body["exercise_slug"] == "squat"
    assert body["repetition_count"] == 3 and len(body["curves"]) == 4 and body["processing"]["analysis"] == "stored"
    kept = db_session.scalar(select(SessionDetail).where(SessionDetail.session_id == session_id))
    document = json.loads(get_store().get(kept.data_key, kept.data_hash))
    assert kept.data_key.startswith("detail/") and document["curves"] == body["curves"]
    assert "session_id" not in document and "started_at" not in document, "the row's own fields are read fresh"
    # the request no longer needs the recording: with the file gone from the store the stored detail is served
    get_store().delete(db_session.get(ExerciseSession, session_id).file_key)
    again = client.get(f"/api/v1/sessions/{session_id}/detail", headers=th)
    assert again.status_code == 200 and again.json() == body


def test_a_changed_metrics_document_makes_the_detail_stale(
    client, make_patient_with_therapist, auth_headers, db_session, run_jobs
):
    patient, therapist = make_patient_with_therapist()
    session_id = _post(client, patient, auth_headers, make_khs("squat", 3, seed=32))
    assert run_jobs() == 1
    th = auth_headers(therapist)
    assert client.get(f"/api/v1/sessions/{session_id}/detail", headers=th).json()["repetition_count"] == 3
    metric = db_session.scalar(select(SessionMetric).where(SessionMetric.session_id == session_id))
    metric.document = dict(metric.document, repetition_list=metric.document["repetition_list"][:2])  # re-analysed
    db_session.flush()
    stale = client.get(f"/api/v1/sessions/{session_id}/detail", headers=th)
    assert stale.status_code == 202, stale.text
    assert run_jobs() == 1
    fresh = client.get(f"/api/v1/sessions/{session_id}/detail", headers=th)
    assert fresh.status_code == 200 and fresh.json()["repetition_count"] == 2
    assert db_session.scalar(select(func.count()).select_from(SessionDetail)) == 1, "the stale one is replaced"


def test_a_stored_file_that_cannot_be_shown_is_said_once_and_not_retried(
    client, make_user, auth_headers, exercise, store, db_session, run_jobs
):
    patient = make_user("patient")
    row = store(patient, exercise, T0, data=b"not a session file")
    headers = auth_headers(patient)
    assert client.get(f"/api/v1/sessions/{row.id}/detail", headers=headers).status_code == 202
    assert run_jobs() == 1
    response = client.get(f"/api/v1/sessions/{row.id}/detail", headers=headers)
    assert response.status_code == 400 and response.json()["error"] == "InvalidSessionFile", response.text
    assert response.json()["detail"].startswith(f"the stored file of session {row.id} cannot be read")
    assert db_session.scalar(select(Job.status).where(Job.kind == "detail")) == "done"
    assert run_jobs() == 0 and db_session.scalar(select(func.count()).select_from(SessionDetail)) == 0


def test_a_failed_build_is_said_in_words_and_asked_again(
    client, make_patient_with_therapist, auth_headers, db_session, run_jobs, object_store
):
    patient, therapist = make_patient_with_therapist()
    session_id = _post(client, patient, auth_headers, make_khs("squat", 2, seed=33))
    row = db_session.get(ExerciseSession, session_id)
    data = object_store.get(row.file_key, row.content_hash)
    object_store.delete(row.file_key)
    job = db_session.scalar(select(Job).where(Job.kind == "detail"))
    for _ in range(3):
        assert run_jobs() == 1
        db_session.refresh(job)
        job.run_after = job.created_at
    assert job.status == "failed"
    th = auth_headers(therapist)
    asked = client.get(f"/api/v1/sessions/{session_id}/detail", headers=th)
    assert asked.status_code == 202 and asked.json()["state"] == "preparing", asked.text
    assert "a worker will try again" in asked.json()["detail"] and "missing from the object store" in asked.json()[
        "detail"]  # fmt: skip
    object_store.put("session", data)
    assert run_jobs() == 1
    assert client.get(f"/api/v1/sessions/{session_id}/detail", headers=th).status_code == 200


def test_a_removed_recording_is_said_as_before(client, make_user, auth_headers, exercise, store, db_session):
    patient = make_user("patient")
    row = store(patient, exercise, T0, data=make_khs("squat", 1, seed=34))
    row.file_key, row.file_bytes, row.file_removed_at = None, None, T0
    db_session.flush()
    response = client.get(f"/api/v1/sessions/{row.id}/detail", headers=auth_headers(patient))
    assert response.status_code == 410 and response.json()["error"] == "SessionFileRemoved", response.text
    assert db_session.scalar(select(func.count()).select_from(Job).where(Job.kind == "detail")) == 0
