"""The admin view of the queue: batches with progress and who queued them, jobs with their state and failures in
words (never a traceback), and the re-analysis of one patient's sessions started over the API."""

from __future__ import annotations

import pytest
import sqlalchemy as sa
from sqlalchemy.orm import Session

from backend.config import Settings
from backend.database import utcnow
from backend.jobs.listing import error_words
from backend.jobs.models import Job
from backend.jobs.worker import work
from backend.sessions.metrics import ANALYSIS_VERSION
from backend.sessions.models import ExerciseSession, SessionMetric
from tests.backend.khs_files import make_processed_khs

SETTINGS = Settings(ENVIRONMENT="local", DATABASE_URL="sqlite://")


def _old(db_session, session_id: int) -> None:
    """Makes a session's document look made by the analysis before versions were recorded."""
    metric = db_session.scalar(sa.select(SessionMetric).where(SessionMetric.session_id == session_id))
    doc = dict(metric.document)
    doc.pop("analysis_version"), doc.pop("schema_version")  # schema 1: neither was recorded
    metric.document = doc
    db_session.flush()


def _sessions(db_connection):
    return lambda: Session(bind=db_connection, join_transaction_mode="create_savepoint", expire_on_commit=False)


def test_an_admin_queues_one_patients_sessions_and_follows_them(client, db_session, db_connection, upload, make_user,
                                                                 auth_headers, object_store):  # fmt: skip
    admin = make_user("admin")
    admin_headers = auth_headers(admin)
    mine, patient, _ = upload(make_processed_khs("shoulder_abduction", 2, seed=7), "shoulder_abduction")
    broken, _, _ = upload(make_processed_khs("shoulder_abduction", 2, seed=8), "shoulder_abduction")
    other, _, _ = upload(make_processed_khs("shoulder_abduction", 2, seed=9), "shoulder_abduction")
    for sid in (mine, broken, other):
        _old(db_session, sid)
    # the broken session belongs to the same patient: its file is gone from the store
    db_session.get(ExerciseSession, broken).patient_id = patient.id
    object_store.delete(db_session.get(ExerciseSession, broken).file_key)
    db_session.commit()
    queued = client.post("/api/v1/reanalysis", json={"patient_id": patient.id}, headers=admin_headers)
    assert queued.status_code == 202, queued.text
    batch = queued.json()["batch"]
    overview = client.get("/api/v1/reanalysis", headers=admin_headers).json()
    assert overview["analysis_version"] == ANALYSIS_VERSION
    row = overview["batches"][0]
    assert (row["batch"], row["queued"], row["total"], row["finished_at"]) == (batch, 2, 2, None)
    assert row["queued_by"] == admin.email and row["patient_id"] == patient.id
    jobs = client.get("/api/v1/jobs", params={"batch": batch}, headers=admin_headers).json()
    assert sorted(j["session_id"] for j in jobs) == sorted([mine, broken]), "only that patient's sessions"
    assert {j["status"] for j in jobs} == {"queued"}
    for _ in range(3):  # the broken one is tried max_attempts times
        work(sessionmaker=_sessions(db_connection), settings=SETTINGS, name="w", once=True)
        db_session.execute(sa.update(Job).where(Job.status == "queued").values(run_after=utcnow()))
        db_session.commit()
    row = client.get("/api/v1/reanalysis", headers=admin_headers).json()["batches"][0]
    assert (row["done"], row["failed"], row["queued"], row["running"]) == (1, 1, 0, 0)
    assert row["finished_at"] is not None
    by_session = {j["session_id"]: j for j in client.get("/api/v1/jobs", params={"batch": batch},
                                                          headers=admin_headers).json()}  # fmt: skip
    assert by_session[mine]["status"] == "done" and by_session[mine]["changed"] is True
    failed = by_session[broken]
    assert failed["status"] == "failed" and failed["attempts"] == 3
    assert failed["error"].startswith("The session's file is missing from the object store"), failed["error"]
    assert "Traceback" not in failed["error"] and "\n" not in failed["error"]
    only_failed = client.get("/api/v1/jobs", params={"status": "failed"}, headers=admin_headers).json()
    assert [j["session_id"] for j in only_failed] == [broken]


@pytest.mark.parametrize("path", ["/api/v1/reanalysis", "/api/v1/jobs"])
def test_a_therapist_may_not_see_the_queue(path, client, make_user, auth_headers):
    response = client.get(path, headers=auth_headers(make_user("therapist")))
    assert response.status_code == 403 and response.json()["error"] == "Forbidden"


def test_errors_are_said_in_words():
    trace = "StoredObjectCorrupt: session/ab/abc does not match its sha256\nTraceback (most recent call last):\n  ..."
    assert error_words(trace) == ("The session's file in the object store is damaged: its checksum does not match: "
                                  "session/ab/abc does not match its sha256")  # fmt: skip
    assert error_words("KeyError: 'rom'\nTraceback") == "The job failed on an unexpected error (KeyError): 'rom'"
    assert error_words(None) is None


def test_an_unknown_patient_or_exercise_is_refused_not_queued_as_nothing(client, db_session, make_user, auth_headers):
    headers = auth_headers(make_user("admin"))
    therapist = make_user("therapist")
    db_session.commit()  # the refused requests roll back their own work only
    for body in ({"patient_id": 987654}, {"patient_id": therapist.id}):
        response = client.post("/api/v1/reanalysis", json=body, headers=headers)
        assert response.status_code == 404 and response.json()["error"] == "PatientNotFound", response.text
        assert response.json()["detail"] == f"no patient with id {body['patient_id']}"
    response = client.post("/api/v1/reanalysis", json={"exercise": "squats"}, headers=headers)
    assert response.status_code == 422 and response.json()["error"] == "InvalidInput", response.text
    assert "no exercise 'squats' in the library" in response.json()["detail"] and "squat," in response.json()["detail"]
    assert db_session.scalar(sa.select(sa.func.count()).select_from(Job)) == 0
