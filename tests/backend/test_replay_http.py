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


def test_a_stored_file_that_cannot_be_read_fails_in_words_at_once_and_nothing_is_stored(
    client, make_user, auth_headers, exercise, store, db_session, run_jobs
):
    patient = make_user("patient")
    row = store(patient, exercise, T0, data=b"not a session file")
    headers = auth_headers(patient)
    assert client.get(f"/api/v1/sessions/{row.id}/replay/state", headers=headers).json()["state"] == "preparing"
    assert run_jobs() == 1
    failed = client.get(f"/api/v1/sessions/{row.id}/replay/state", headers=headers).json()
    assert failed["state"] == "failed", failed
    assert failed["detail"] == "The stored session file cannot be read.", "a patient: the sentence, not the program's"
    assert "Traceback" not in failed["detail"]
    assert run_jobs() == 0, "no retry reads the same bytes otherwise"
    assert db_session.scalar(select(func.count()).select_from(SessionReplay)) == 0


def test_asking_after_a_failed_build_queues_it_again_a_few_times(client, make_user, auth_headers, exercise, store,
                                                                 db_session, run_jobs, object_store):  # fmt: skip
    patient = make_user("patient")
    data = make_khs("squat", 1, seed=25)
    row = store(patient, exercise, T0, data=data)
    obj = object_store.put("session", data)
    row.file_key, row.content_hash, row.file_bytes = obj.key, obj.sha256, None
    db_session.flush()
    headers = auth_headers(patient)
    object_store.delete(obj.key)  # the store lost the file for a while (a passing fault)
    state = lambda: client.get(f"/api/v1/sessions/{row.id}/replay/state", headers=headers).json()  # noqa: E731
    assert state()["state"] == "preparing"
    job = db_session.scalar(select(Job).where(Job.kind == "replay"))
    for _ in range(3):  # the queue's own tries, without their delays
        assert run_jobs() == 1
        db_session.refresh(job)
        job.run_after = utcnow()
    assert job.status == "failed" and job.attempts == 3
    asked = state()
    assert asked["state"] == "preparing" and "a worker will try again" in asked["detail"], asked
    assert "missing from the object store" in asked["detail"], "the error in words while it is tried again"
    assert run_jobs() == 1
    db_session.refresh(job)
    assert (job.status, job.attempts) == ("failed", 4), "one more try per ask"
    for attempts in (5, 6):
        assert state()["state"] == "preparing"
        assert run_jobs() == 1
        db_session.refresh(job)
        assert (job.status, job.attempts) == ("failed", attempts)
    given_up = state()
    assert given_up["state"] == "failed" and given_up["detail"].endswith("(tried 6 times)"), given_up
    assert run_jobs() == 0, "no try beyond the bound"
    job.status, job.attempts = "failed", 3  # another failure that is still within the bound, and the file is back
    object_store.put("session", data)
    db_session.flush()
    assert state()["state"] == "preparing" and run_jobs() == 1
    assert state()["state"] == "ready"


def test_one_skeleton_alone_is_built_by_a_worker_and_stored(
    client, make_patient_with_therapist, auth_headers, exercise, store, db_session, run_jobs
):
    patient, therapist = make_patient_with_therapist()
    row = store(patient, exercise, T0, data=make_khs("squat", 2, seed=22))
    headers = auth_headers(therapist)
    for layer in ("raw", "filtered"):
        first = client.get(f"/api/v1/sessions/{row.id}/replay?layer={layer}", headers=headers)
        assert first.status_code == 202 and first.json()["state"] == "preparing", first.text
        state = client.get(f"/api/v1/sessions/{row.id}/replay/state?layer={layer}", headers=headers)
        assert state.json()["state"] == "preparing"
    assert db_session.scalar(select(func.count()).select_from(SessionReplay)) == 0, "nothing built in a request"
    keys = set(db_session.scalars(select(Job.key).where(Job.kind == "replay")))
    assert keys == {f"replay:{row.id}:{scene.VERSION}:raw", f"replay:{row.id}:{scene.VERSION}:filtered"}
    assert run_jobs() == 2
    both = client.get(f"/api/v1/sessions/{row.id}/replay/state", headers=headers).json()
    assert both["state"] == "preparing", "the recording of both skeletons is a build of its own"
    raw_answer = client.get(f"/api/v1/sessions/{row.id}/replay?layer=raw", headers=headers)
    assert raw_answer.status_code == 200, raw_answer.text
    raw = read_viser(raw_answer.content)
    assert node_points(raw, "/raw/joints") and not node_points(raw, "/filtered/joints")
    filtered = read_viser(client.get(f"/api/v1/sessions/{row.id}/replay?layer=filtered", headers=headers).content)
    assert node_points(filtered, "/filtered/joints") and not node_points(filtered, "/raw/joints")
    stored = {r.layers: r for r in db_session.scalars(select(SessionReplay).where(SessionReplay.session_id == row.id))}
    assert set(stored) == {"raw", "filtered"}
    assert get_store().get(stored["raw"].data_key, stored["raw"].data_hash) == raw_answer.content
    assert client.get(f"/api/v1/sessions/{row.id}/replay/state?layer=raw", headers=headers).json()["state"] == "ready"
    assert run_jobs() == 1  # the one of both skeletons
    assert db_session.scalar(select(func.count()).select_from(SessionReplay)) == 3
    bad = client.get(f"/api/v1/sessions/{row.id}/replay?layer=both", headers=headers)
    assert bad.status_code == 422 and "layer" in bad.json()["detail"]
