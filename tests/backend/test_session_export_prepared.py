"""GET /sessions/{id}/export of a long recording is prepared by a worker and stored, never built in the request: 202
while it builds, then the stored file, byte for byte the one the request builds for a short recording; a failed
build is said in words and asked again, and leaves nothing stored. Here "long" is anything over 50 frames (the
server's limits are lowered so that short simulated sets take the worker's path and the tests stay fast)."""

from __future__ import annotations

import datetime as dt
import gzip
import json
import re
from typing import Any

import pytest
from sqlalchemy import func, select

from backend.audit.models import AuditEvent
from backend.config import Settings
from backend.exercises.models import Exercise
from backend.jobs.models import Job
from backend.records.retention import apply_retention
from backend.sessions.encoding import accepts_gzip
from backend.sessions.models import ExerciseSession, SessionExport
from backend.sessions.prepared_export import in_request
from tests.backend.khs_files import make_khs

T0 = dt.datetime(2026, 11, 2, 9, 0, tzinfo=dt.UTC)
DIRECT_MAX_FRAMES = 50  # the simulated sets below have 100-300 frames


@pytest.fixture
def settings() -> Settings:
    """The test app's settings with exports built in the request only up to DIRECT_MAX_FRAMES frames."""
    return Settings(ENVIRONMENT="local", CHECK_MIGRATIONS=False, DATABASE_URL="sqlite://", EVENTS_STREAM_MAX_S=0.0,
                    LIVE_OFFLINE_GRACE_S=0.0, LIVE_WARM_UP=False,
                    EXPORT_DIRECT_MAX_FRAMES=DIRECT_MAX_FRAMES)  # fmt: skip


@pytest.fixture
def stored(db_session, store, make_patient_with_therapist):
    """Factory: stored(seed) -> (session id, patient, therapist): a simulated squat set stored as an upload stores it
    (file, metrics), without the upload's own work (the detail build), so the tests stay fast."""
    squat = db_session.scalar(select(Exercise).where(Exercise.slug == "squat"))

    def make(seed: int):
        patient, therapist = make_patient_with_therapist()
        return store(patient, squat, T0, data=make_khs("squat", 2, seed=seed)).id, patient, therapist

    return make


def _export(client, session_id: int, fmt: str, headers: dict[str, Any]):
    return client.get(f"/api/v1/sessions/{session_id}/export", params={"format": fmt}, headers=headers)


def _count(db_session, model, *where) -> int:
    return db_session.scalar(select(func.count()).select_from(model).where(*where))


@pytest.mark.parametrize(
    ("header", "gzip_ok"),
    [("gzip, deflate", True), ("br;q=1.0, GZIP;q=0.5", True), ("gzip;q=0", False), ("identity", False),
     ("*", True), (None, False), ("gzip;q=x", False)],
)  # fmt: skip
def test_accept_encoding_allows_gzip_only_when_listed_with_a_weight(header, gzip_ok):
    assert accepts_gzip(header) is gzip_ok


def test_the_request_builds_only_a_recording_short_in_both_duration_and_frames():
    def within(duration_s: float, n_frames: int) -> bool:
        return in_request(duration_s=duration_s, n_frames=n_frames, max_s=300.0, max_frames=9000)

    assert within(300.0, 9000)
    assert not within(7200.0, 9000), "few frames over two hours: the worker"
    assert not within(60.0, 216_000), "many frames in a minute: the worker"


def test_a_long_session_answers_202_then_the_file_a_worker_stored(
    client, stored, auth_headers, db_session, run_jobs, object_store
):
    session_id, _, therapist = stored(41)
    th = auth_headers(therapist)
    first = _export(client, session_id, "bvh", th)
    assert first.status_code == 202 and first.headers["retry-after"] == "5", first.text
    assert set(first.json()) == {"state", "detail"} and first.json()["state"] == "preparing"
    assert "motion (BVH) file is queued" in first.json()["detail"], first.json()
    assert _export(client, session_id, "bvh", th).status_code == 202
    assert _count(db_session, SessionExport) == 0, "nothing built in a request"
    assert _count(db_session, Job, Job.kind == "export") == 1, "queued once"
    assert run_jobs() == 1
    ready = _export(client, session_id, "bvh", th)
    assert ready.status_code == 200, ready.text
    assert ready.headers["content-type"] == "text/plain; charset=utf-8"
    assert ready.headers["content-disposition"] == f'attachment; filename="session-{session_id}.bvh"'
    assert ready.headers["content-encoding"] == "gzip", "handed out as stored: the request compresses nothing"
    kept = db_session.scalar(select(SessionExport).where(SessionExport.session_id == session_id))
    assert kept.format == "bvh" and kept.data_key.startswith("export/")
    assert gzip.decompress(object_store.get(kept.data_key, kept.data_hash)) == ready.content
    plain = client.get(f"/api/v1/sessions/{session_id}/export", params={"format": "bvh"},
                       headers=th | {"Accept-Encoding": "identity"})  # fmt: skip
    assert plain.status_code == 200 and "content-encoding" not in plain.headers and plain.content == ready.content
    reads = (AuditEvent.action == "session.export.read", AuditEvent.object_id == str(session_id))
    audited = db_session.scalars(select(AuditEvent.detail).where(*reads)).all()
    assert audited == [{"format": "bvh"}] * 2, "audited when the file is handed out, not while it is prepared"
    assert run_jobs() == 0 and _export(client, session_id, "bvh", th).content == ready.content


def _fhir_without_fresh_ids(body: bytes) -> dict[str, Any]:
    """Returns a FHIR bundle with its urn:uuid ids numbered in order and its timestamp dropped (both new each build)."""
    seen: dict[str, str] = {}
    text = re.sub(r"urn:uuid:[0-9a-f-]{36}", lambda m: seen.setdefault(m.group(0), f"urn:{len(seen)}"), body.decode())
    bundle = json.loads(text)
    bundle.pop("timestamp")
    return bundle


@pytest.mark.parametrize("fmt", ["csv", "trc", "bvh", "fhir"])
def test_the_stored_export_is_the_file_the_request_builds_for_a_short_session(
    client, stored, auth_headers, run_jobs, settings, fmt
):
    session_id, patient, _ = stored(42)
    headers = auth_headers(patient)
    assert _export(client, session_id, fmt, headers).status_code == 202
    assert run_jobs() == 1
    stored = _export(client, session_id, fmt, headers)
    settings.EXPORT_DIRECT_MAX_FRAMES = 10**6  # the same session now short enough: built in the request
    direct = _export(client, session_id, fmt, headers)
    assert stored.status_code == direct.status_code == 200, (stored.text, direct.text)
    for name in ("content-type", "content-disposition"):
        assert stored.headers[name] == direct.headers[name]
    if fmt == "fhir":
        assert _fhir_without_fresh_ids(stored.content) == _fhir_without_fresh_ids(direct.content)
    else:
        assert stored.content == direct.content, f"{fmt}: {len(stored.content)} against {len(direct.content)} bytes"


def test_a_new_answer_about_the_set_makes_the_stored_csv_stale(client, stored, auth_headers, db_session, run_jobs):
    session_id, patient, therapist = stored(43)
    th = auth_headers(therapist)
    assert _export(client, session_id, "csv", th).status_code == 202 and run_jobs() == 1
    before = _export(client, session_id, "csv", th)
    answered = client.put(f"/api/v1/sessions/{session_id}/feeling", json={"pain": 4, "effort": 5},
                          headers=auth_headers(patient))  # fmt: skip
    assert before.status_code == 200 and answered.status_code == 200, answered.text
    assert _export(client, session_id, "csv", th).status_code == 202, "made from what the patient said before"
    assert run_jobs() == 1
    after = _export(client, session_id, "csv", th)
    assert after.status_code == 200 and after.content != before.content
    assert _count(db_session, SessionExport) == 1, "the stale file is replaced"


def test_a_failed_build_is_said_in_words_asked_again_and_leaves_nothing_stored(
    client, upload, auth_headers, db_session, run_jobs, object_store
):
    session_id, _, therapist = upload(make_khs("squat", 2, seed=44), "squat")
    row = db_session.get(ExerciseSession, session_id)
    data = object_store.get(row.file_key, row.content_hash)
    exports_before = {k for k in object_store.keys() if k.startswith("export/")}
    object_store.delete(row.file_key)
    th = auth_headers(therapist)
    assert _export(client, session_id, "trc", th).status_code == 202
    job = db_session.scalar(select(Job).where(Job.kind == "export"))
    for _ in range(3):
        assert run_jobs() == 1
        db_session.refresh(job)
        job.run_after = job.created_at
    assert job.status == "failed"
    assert _count(db_session, SessionExport) == 0
    assert {k for k in object_store.keys() if k.startswith("export/")} == exports_before, "no object of a failed build"
    asked = _export(client, session_id, "trc", th)
    assert asked.status_code == 202 and asked.json()["state"] == "preparing", asked.text
    detail = asked.json()["detail"]
    assert "a worker will try again" in detail and "missing from the object store" in detail, detail
    object_store.put("session", data)
    assert run_jobs() == 1
    ready = _export(client, session_id, "trc", th)
    assert ready.status_code == 200 and ready.content.startswith(b"PathFileType"), ready.text[:200]


def test_a_format_the_session_cannot_give_is_said_once_and_not_retried(
    client, db_session, store, make_patient_with_therapist, auth_headers, run_jobs
):
    patient, therapist = make_patient_with_therapist()
    unknown = Exercise(slug="not_in_library", name="N", instructions="-", defining_angles=["knee_flexion_L"],
                       plane="sagittal", normal_range_min_deg=0.0, normal_range_max_deg=90.0,
                       pose="standing")  # fmt: skip
    db_session.add(unknown)
    db_session.flush()
    row = store(patient, unknown, T0, data=make_khs("squat", 2, seed=45), metrics=False)
    headers = auth_headers(therapist)
    assert _export(client, row.id, "fhir", headers).status_code == 202
    assert run_jobs() == 1
    response = _export(client, row.id, "fhir", headers)
    assert response.status_code == 409 and response.json()["error"] == "ExportUnavailable", response.text
    assert "analysis document" in response.json()["detail"]
    assert run_jobs() == 0 and _count(db_session, SessionExport) == 0


@pytest.mark.parametrize("role", ["patient", "therapist"])
def test_someone_else_gets_404_and_queues_nothing(client, store, make_user, auth_headers, exercise, db_session, role):
    session_id = store(make_user("patient"), exercise, T0, data=make_khs("squat", 2, seed=46)).id  # 900 frames
    response = _export(client, session_id, "bvh", auth_headers(make_user(role)))
    assert response.status_code == 404
    assert response.json() == {"error": "SessionNotFound", "detail": f"session {session_id} does not exist"}
    assert _count(db_session, Job, Job.kind == "export") == 0


def test_a_removed_recording_is_410_and_queues_nothing(client, make_user, auth_headers, exercise, store, db_session):
    patient = make_user("patient")
    row = store(patient, exercise, T0, data=make_khs("squat", 1, seed=47))
    row.file_key, row.file_bytes, row.file_removed_at = None, None, T0
    db_session.flush()
    response = _export(client, row.id, "csv", auth_headers(patient))
    assert response.status_code == 410 and response.json()["error"] == "SessionFileRemoved", response.text
    assert _count(db_session, Job, Job.kind == "export") == 0


def _stored_export(client, db_session, run_jobs, session_id: int, headers: dict[str, Any]) -> str:
    """Has a worker build the session's BVH; returns its object key."""
    assert _export(client, session_id, "bvh", headers).status_code == 202 and run_jobs() == 1
    return db_session.scalar(select(SessionExport.data_key).where(SessionExport.session_id == session_id))


def test_retention_and_erasure_remove_the_stored_exports(
    client, stored, make_user, auth_headers, db_session, run_jobs, object_store
):
    old_id, _, therapist = stored(48)
    th = auth_headers(therapist)
    old_key = _stored_export(client, db_session, run_jobs, old_id, th)
    db_session.get(ExerciseSession, old_id).started_at = dt.datetime(2025, 1, 1, tzinfo=dt.UTC)
    db_session.flush()
    apply_retention(db_session=db_session, days=365, now=dt.datetime(2026, 11, 27, tzinfo=dt.UTC))
    db_session.commit()
    assert not object_store.exists(old_key) and _count(db_session, SessionExport) == 0
    assert _export(client, old_id, "bvh", th).status_code == 410
    new_id, patient, _ = stored(49)
    key = _stored_export(client, db_session, run_jobs, new_id, auth_headers(patient))
    erased = client.post(f"/api/v1/patients/{patient.id}/erasure", json={"confirm_email": patient.email},
                         headers=auth_headers(make_user("admin")))  # fmt: skip
    assert erased.status_code == 200 and erased.json()["rows"]["session_export"] == 1, erased.text
    assert not object_store.exists(key) and _count(db_session, SessionExport) == 0
