"""GET /api/v1/sessions/{id}/replay: the session's viser recording, built once and kept for every worker."""

from __future__ import annotations

import datetime as dt

from sqlalchemy import func, select

from backend.audit.models import AuditEvent
from backend.database import utcnow
from backend.jobs.models import Job
from backend.replay import scene
from backend.replay.models import SessionReplay
from backend.storage import get_store
from tests.backend.khs_files import make_khs
from tests.backend.replay.viser_file import node_points, read_viser

T0 = dt.datetime(2026, 11, 2, 9, 0, tzinfo=dt.UTC)


def test_the_recording_is_built_by_a_worker_once_and_served_to_everyone(
    client, make_patient_with_therapist, auth_headers, exercise, store, db_session, run_jobs
):
    patient, therapist = make_patient_with_therapist()
    row = store(patient, exercise, T0, data=make_khs("squat", 2, seed=21))
    th, pa = auth_headers(therapist), auth_headers(patient)
    first = client.get(f"/api/v1/sessions/{row.id}/replay", headers=th)
    assert first.status_code == 202 and first.headers["retry-after"] == "2", first.text
    assert first.json()["state"] == "preparing" and "queued" in first.json()["detail"]
    for headers in (th, pa, th):  # however many ask, one build is queued
        state = client.get(f"/api/v1/sessions/{row.id}/replay/state", headers=headers)
        assert state.status_code == 200 and state.json()["state"] == "preparing", state.text
    assert db_session.scalar(select(func.count()).select_from(Job).where(Job.kind == "replay")) == 1
    assert db_session.scalar(select(func.count()).select_from(SessionReplay)) == 0, "nothing built in a request"
    assert run_jobs() == 1
    assert client.get(f"/api/v1/sessions/{row.id}/replay/state", headers=pa).json()["state"] == "ready"
    ready = client.get(f"/api/v1/sessions/{row.id}/replay", headers=th)
    assert ready.status_code == 200 and ready.headers["content-type"] == "application/octet-stream"
    doc = read_viser(ready.content)
    assert doc["durationSeconds"] > 1.0 and node_points(doc, "/filtered/joints") and node_points(doc, "/raw/joints")
    stored = db_session.scalar(select(SessionReplay).where(SessionReplay.session_id == row.id))
    assert stored is not None and stored.version == scene.VERSION and stored.size == len(ready.content)
    again = client.get(f"/api/v1/sessions/{row.id}/replay", headers=pa)
    assert again.status_code == 200 and again.content == ready.content
    assert db_session.scalar(select(func.count()).select_from(SessionReplay)) == 1
    actions = db_session.scalars(select(AuditEvent.action).where(AuditEvent.object_id == str(row.id))).all()
    assert actions.count("session.replay.read") == 2, "a 202 is no read of the recording"


def test_a_job_run_twice_builds_once(client, make_user, auth_headers, exercise, store, db_session, run_jobs):
    patient = make_user("patient")
    row = store(patient, exercise, T0, data=make_khs("squat", 1, seed=24))
    assert client.get(f"/api/v1/sessions/{row.id}/replay", headers=auth_headers(patient)).status_code == 202
    assert run_jobs() == 1
    key = db_session.scalar(select(SessionReplay.data_key).where(SessionReplay.session_id == row.id))
    job = db_session.scalar(select(Job).where(Job.kind == "replay"))
    job.status = "queued"  # its worker died after the build, before marking it done
    assert run_jobs() == 1
    assert db_session.scalar(select(Job.result).where(Job.kind == "replay"))["built"] is False
    assert db_session.scalar(select(SessionReplay.data_key).where(SessionReplay.session_id == row.id)) == key


def test_a_recording_of_an_older_version_is_rebuilt(client, make_user, auth_headers, exercise, store, db_session,
                                                     run_jobs):  # fmt: skip
    patient = make_user("patient")
    row = store(patient, exercise, T0, data=make_khs("squat", 2, seed=22))
    db_session.add(SessionReplay(session_id=row.id, version="replay-0", data=b"old", size=3, n_frames=1,
                                 duration_s=0.0, view="side"))  # fmt: skip
    db_session.flush()
    headers = auth_headers(patient)
    assert client.get(f"/api/v1/sessions/{row.id}/replay", headers=headers).status_code == 202
    assert run_jobs() == 1
    response = client.get(f"/api/v1/sessions/{row.id}/replay", headers=headers)
    assert response.status_code == 200 and response.content != b"old"
    stored = db_session.scalar(select(SessionReplay).where(SessionReplay.session_id == row.id))
    assert stored.version == scene.VERSION and stored.data is None  # the recording is in the object store
    assert get_store().get(stored.data_key, stored.data_hash) == response.content


def test_no_login_is_401_and_another_patient_is_404(client, make_user, auth_headers, exercise, store):
    patient, stranger = make_user("patient"), make_user("patient")
    row = store(patient, exercise, T0, data=make_khs("squat", 1, seed=23))
    headers = auth_headers(stranger)  # made before any error response rolls the test's transaction back
    response = client.get(f"/api/v1/sessions/{row.id}/replay", headers=headers)
    assert response.status_code == 404, response.text
    response = client.get(f"/api/v1/sessions/{row.id}/replay")
    assert response.status_code == 401 and response.json()["error"] == "NotAuthenticated"


def test_missing_session_is_404(client, make_user, auth_headers):
    response = client.get("/api/v1/sessions/987654/replay", headers=auth_headers(make_user("admin")))
    assert response.status_code == 404 and response.json()["error"] == "SessionNotFound"


def test_a_stored_file_that_cannot_be_read_fails_in_words_and_nothing_is_stored(
    client, make_user, auth_headers, exercise, store, db_session, run_jobs
):
    patient = make_user("patient")
    row = store(patient, exercise, T0, data=b"not a session file")
    headers = auth_headers(patient)
    assert client.get(f"/api/v1/sessions/{row.id}/replay/state", headers=headers).json()["state"] == "preparing"
    assert run_jobs() == 1
    retry = client.get(f"/api/v1/sessions/{row.id}/replay/state", headers=headers).json()
    assert retry["state"] == "preparing" and "a worker will try again" in retry["detail"], retry
    assert f"The stored session file cannot be read: the stored file of session {row.id}" in retry["detail"]
    job = db_session.scalar(select(Job).where(Job.kind == "replay"))
    job.max_attempts, job.run_after = 1, utcnow()  # no waiting for the retry delays
    assert run_jobs() == 1
    failed = client.get(f"/api/v1/sessions/{row.id}/replay/state", headers=headers).json()
    assert failed["state"] == "failed" and failed["detail"].startswith("The stored session file cannot be read")
    assert "Traceback" not in failed["detail"]
    assert db_session.scalar(select(func.count()).select_from(SessionReplay)) == 0


def test_one_skeleton_alone_is_built_without_the_other_and_not_stored(
    client, make_patient_with_therapist, auth_headers, exercise, store, db_session
):
    patient, therapist = make_patient_with_therapist()
    row = store(patient, exercise, T0, data=make_khs("squat", 2, seed=22))
    headers = auth_headers(therapist)
    raw = read_viser(client.get(f"/api/v1/sessions/{row.id}/replay?layer=raw", headers=headers).content)
    assert node_points(raw, "/raw/joints") and not node_points(raw, "/filtered/joints")
    filtered = read_viser(client.get(f"/api/v1/sessions/{row.id}/replay?layer=filtered", headers=headers).content)
    assert node_points(filtered, "/filtered/joints") and not node_points(filtered, "/raw/joints")
    assert db_session.scalar(select(func.count()).select_from(SessionReplay)) == 0
    bad = client.get(f"/api/v1/sessions/{row.id}/replay?layer=both", headers=headers)
    assert bad.status_code == 422 and "layer" in bad.json()["detail"]
