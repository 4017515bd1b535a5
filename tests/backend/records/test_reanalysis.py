"""Re-analysis on the job queue: idempotent jobs, old metrics kept beside new, a crashed worker's job taken again,
failures retried then recorded; with the pipeline, a file not filtered by today's pipeline filtered again into a new
file, the earlier one kept."""

from __future__ import annotations

import datetime as dt
import io
import json
import uuid
import zipfile

import numpy as np
import sqlalchemy as sa
from sqlalchemy.orm import Session

from backend.config import Settings
from backend.database import utcnow
from backend.jobs import queue
from backend.jobs.models import Job, SessionMetricVersion
from backend.jobs.worker import work
from backend.records.reanalysis import enqueue_reanalysis
from backend.records.retention import apply_retention
from backend.replay.models import SessionReplay
from backend.replay.service import build_and_store
from backend.sessions.metrics import ANALYSIS_VERSION
from backend.sessions.models import ExerciseSession, SessionMetric
from backend.storage.check import check
from kinect_agent.capture import make_payload
from kinect_agent.formats import session_file as sf
from kinect_agent.processing.config import PipelineConfig, config_for_device
from kinect_agent.processing.pipeline import VERSION
from kinect_agent.sources.simulator import simulate
from tests.backend.khs_files import make_khs, make_processed_khs

SETTINGS = Settings(ENVIRONMENT="local", DATABASE_URL="sqlite://")


def _old_session(client, db_session, upload):
    """An uploaded session whose document looks made by the analysis before versions (no balance, other ROM)."""
    session_id, patient, therapist = upload(make_processed_khs("shoulder_abduction", 3, seed=5), "shoulder_abduction")
    metric = db_session.scalar(sa.select(SessionMetric).where(SessionMetric.session_id == session_id))
    old = dict(metric.document, balance=None, rom_deg=1.0)
    old.pop("analysis_version"), old.pop("schema_version")  # stored before either was recorded: schema 1
    metric.document, metric.rom_deg = old, 1.0
    db_session.flush()
    return session_id, patient, therapist


def _sessions(db_connection):
    return lambda: Session(bind=db_connection, join_transaction_mode="create_savepoint", expire_on_commit=False)


def test_a_worker_reanalyses_and_keeps_the_old_metrics(client, db_session, db_connection, upload, auth_headers):
    session_id, patient, therapist = _old_session(client, db_session, upload)
    batch, added = enqueue_reanalysis(db_session=db_session, patient_id=patient.id)
    assert added == 1
    assert enqueue_reanalysis(db_session=db_session, patient_id=patient.id)[1] == 0, "the same work is queued once"
    db_session.commit()
    assert work(sessionmaker=_sessions(db_connection), settings=SETTINGS, name="w1", once=True) == 1
    db_session.expire_all()
    assert queue.progress(db_session=db_session, batch=batch) == {"queued": 0, "running": 0, "done": 1, "failed": 0,
                                                                  "total": 1}  # fmt: skip
    metric = db_session.scalar(sa.select(SessionMetric).where(SessionMetric.session_id == session_id))
    assert metric.document["analysis_version"] == ANALYSIS_VERSION and metric.rom_deg > 10
    assert metric.document["balance"]["sway_velocity_m_s"] > 0
    old = db_session.scalars(sa.select(SessionMetricVersion).where(SessionMetricVersion.session_id == session_id))
    assert [(v.analysis_version, v.document["rom_deg"]) for v in old] == [("before 2026.11.27", 1.0)]
    versions = client.get(f"/api/v1/sessions/{session_id}/metric-versions", headers=auth_headers(therapist)).json()
    assert [(v["current"], v["rom_deg"]) for v in versions] == [(True, metric.rom_deg), (False, 1.0)]
    assert versions[1]["balance_sway_m_s"] is None and versions[0]["balance_sway_m_s"] > 0
    # a job run again (its worker died after the work, before marking it done) changes nothing
    job = db_session.scalar(sa.select(Job).where(Job.batch == batch))
    job.status = "queued"
    db_session.commit()
    assert work(sessionmaker=_sessions(db_connection), settings=SETTINGS, name="w2", once=True) == 1
    db_session.expire_all()
    assert db_session.scalar(sa.select(Job.result).where(Job.batch == batch))["changed"] is False
    assert db_session.scalar(sa.select(sa.func.count()).select_from(SessionMetricVersion)
                             .where(SessionMetricVersion.session_id == session_id)) == 1  # fmt: skip


def test_the_job_of_a_crashed_worker_is_taken_again_after_its_lease(db_session, upload, client):
    _, patient, _ = _old_session(client, db_session, upload)
    enqueue_reanalysis(db_session=db_session, patient_id=patient.id)
    db_session.commit()
    first = queue.claim(db_session=db_session, worker="dies", kinds=("reanalyze",))
    assert first is not None and first.status == "running"
    assert queue.claim(db_session=db_session, worker="other", kinds=("reanalyze",)) is None, "leased: not taken"
    later = utcnow() + queue.LEASE + dt.timedelta(seconds=1)
    again = queue.claim(db_session=db_session, worker="other", kinds=("reanalyze",), now=later)
    assert again is not None and again.id == first.id and again.locked_by == "other" and again.attempts == 2


def test_a_failing_job_is_retried_then_recorded(db_session, db_connection, upload, client, object_store):
    session_id, patient, _ = _old_session(client, db_session, upload)
    object_store.delete(db_session.get(ExerciseSession, session_id).file_key)
    enqueue_reanalysis(db_session=db_session, patient_id=patient.id)
    db_session.commit()
    for attempt in range(1, 4):
        assert work(sessionmaker=_sessions(db_connection), settings=SETTINGS, name="w", once=True) == 1
        db_session.expire_all()
        job = db_session.scalar(sa.select(Job).where(Job.payload["session_id"].as_integer() == session_id,
                                                     Job.kind == "reanalyze"))  # fmt: skip
        assert job.attempts == attempt and "StoredObjectMissing" in job.error
        if attempt < 3:
            assert job.status == "queued" and job.run_after > utcnow()
            job.run_after = utcnow()
            db_session.commit()
    assert job.status == "failed"


def test_a_failed_reanalysis_is_queued_again_once_asked_again(db_session, db_connection, upload, client, object_store):
    """A clinic restores the missing file from its backup and runs `coach-server reanalyze` again: the failed job gets
    fresh tries in the new batch; a done job is not queued again."""
    session_id, patient, _ = _old_session(client, db_session, upload)
    key = db_session.get(ExerciseSession, session_id).file_key
    data = object_store.get(key, db_session.get(ExerciseSession, session_id).content_hash)
    object_store.delete(key)
    first, _ = enqueue_reanalysis(db_session=db_session, patient_id=patient.id)
    db_session.execute(sa.update(Job).values(max_attempts=1))  # fail at once
    db_session.commit()
    assert work(sessionmaker=_sessions(db_connection), settings=SETTINGS, name="w", once=True) == 1
    assert queue.progress(db_session=db_session, batch=first)["failed"] == 1
    object_store.put("session", data)  # restored
    second, added = enqueue_reanalysis(db_session=db_session, patient_id=patient.id)
    db_session.commit()
    assert added == 1 and queue.progress(db_session=db_session, batch=second)["queued"] == 1
    job = db_session.scalar(sa.select(Job).where(Job.batch == second))
    assert (job.attempts, job.error, job.finished_at) == (0, None, None)
    assert work(sessionmaker=_sessions(db_connection), settings=SETTINGS, name="w", once=True) == 1
    db_session.expire_all()
    assert queue.progress(db_session=db_session, batch=second)["done"] == 1
    assert db_session.scalar(sa.select(SessionMetric.document).where(SessionMetric.session_id == session_id))[
        "analysis_version"] == ANALYSIS_VERSION  # fmt: skip
    assert enqueue_reanalysis(db_session=db_session, patient_id=patient.id)[1] == 0, "done: not queued again"


# ---------------------------------------------------------------------------------------------- with the pipeline


def _file(db_session, object_store, session_id):
    """Returns the decoded current session file of a session and its row."""
    row = db_session.get(ExerciseSession, session_id)
    return sf.decode(object_store.get(row.file_key, row.content_hash)), row


def _pipeline_job(client, db_session, db_connection, make_user, auth_headers, patient_id):
    """Queues a re-analysis with the pipeline through the admin API, runs a worker; returns the batch's jobs."""
    admin = auth_headers(make_user("admin"))
    queued = client.post("/api/v1/reanalysis", json={"patient_id": patient_id, "pipeline": True}, headers=admin)
    assert queued.status_code == 202, queued.text
    db_session.commit()
    work(sessionmaker=_sessions(db_connection), settings=SETTINGS, name="w", once=True)
    db_session.expire_all()
    return client.get("/api/v1/jobs", params={"batch": queued.json()["batch"]}, headers=admin).json()


def test_the_pipeline_filters_a_file_of_no_known_pipeline_again_and_keeps_the_earlier_file(
    client, db_session, db_connection, upload, make_user, auth_headers, object_store
):
    data = make_khs("squat", 3, seed=7)  # filtered = the simulator's truth, params name no pipeline
    session_id, patient, therapist = upload(data, "squat")
    before, row = _file(db_session, object_store, session_id)
    old_key, old_hash = row.file_key, row.content_hash
    build_and_store(db_session=db_session, session_id=session_id, max_frames=SETTINGS.SESSION_MAX_FRAMES,
                    max_decoded_bytes=SETTINGS.SESSION_MAX_DECODED_BYTES, layers=("filtered",))  # fmt: skip
    old_replay = db_session.scalar(sa.select(SessionReplay.data_key).where(SessionReplay.session_id == session_id))
    assert old_replay in object_store.keys()
    (job,) = _pipeline_job(client, db_session, db_connection, make_user, auth_headers, patient.id)
    assert (job["status"], job["changed"]) == ("done", True), job
    after, row = _file(db_session, object_store, session_id)
    assert row.content_hash != old_hash and row.file_key != old_key
    np.testing.assert_array_equal(after.raw.positions, before.raw.positions, err_msg="the raw recording is kept")
    np.testing.assert_array_equal(after.raw.state, before.raw.state)
    np.testing.assert_allclose(after.raw.t, before.raw.t, atol=1e-9)
    assert after.params["pipeline"] == VERSION and after.params["config"] == json.loads(
        json.dumps(config_for_device(after.raw.meta.device).model_dump()))  # fmt: skip
    assert after.params["refiltered"] == {"from_sha256": old_hash, "reason": "filtered by an unnamed pipeline"}
    assert after.params["filter"] == "test", "the file's other params are kept"
    assert after.angle_sd is not None and after.filtered.meta.history[-1].startswith(VERSION)
    moved = np.nanmedian(np.linalg.norm(after.filtered.positions - before.filtered.positions, axis=-1))
    assert moved > 0.002, f"the new filtered recording is the pipeline's, not the truth again ({moved} m)"
    assert row.processing_params["pipeline"] == VERSION
    assert db_session.scalar(sa.select(SessionReplay.id).where(SessionReplay.session_id == session_id)) is None
    assert old_replay not in object_store.keys(), "the replay of the earlier file is dropped (rebuilt when asked)"
    (earlier,) = db_session.scalars(
        sa.select(SessionMetricVersion).where(SessionMetricVersion.session_id == session_id)
    )
    assert (earlier.file_key, earlier.file_hash) == (old_key, old_hash)
    assert object_store.get(earlier.file_key, earlier.file_hash) == data, "the earlier file stays retrievable"
    assert earlier.processing_params == {"filter": "test"} and earlier.analysis_version == ANALYSIS_VERSION
    versions = client.get(f"/api/v1/sessions/{session_id}/metric-versions", headers=auth_headers(therapist)).json()
    assert [(v["current"], v["file_sha256"], v["pipeline_version"], v["file_kept"]) for v in versions] == [
        (True, row.content_hash, VERSION, True), (False, old_hash, None, True)]  # fmt: skip
    assert versions[0]["refiltered"] == "filtered by an unnamed pipeline" and versions[1]["refiltered"] is None
    assert versions[0]["pipeline_settings"] is not None and versions[1]["pipeline_settings"] is None
    report = check(db_connection, object_store)
    assert report.ok and old_key not in report.orphans and row.file_key not in report.orphans
    # the agent sends its own file again (a retry after a lost answer): the same session, no conflict
    again = client.post("/api/v1/sessions", content=data, params={"exercise": "squat"},
                        headers={"Content-Type": "application/octet-stream", **auth_headers(patient)})  # fmt: skip
    assert again.status_code == 200 and again.json()["id"] == session_id, again.text
    # run again (a new batch, or the job repeated after a crash): nothing changes
    job_row = db_session.scalar(sa.select(Job).where(Job.payload["session_id"].as_integer() == session_id,
                                                     Job.kind == "reanalyze"))  # fmt: skip
    job_row.status = "queued"
    db_session.commit()
    assert work(sessionmaker=_sessions(db_connection), settings=SETTINGS, name="w2", once=True) == 1
    db_session.expire_all()
    assert db_session.scalar(sa.select(Job.result).where(Job.id == job_row.id))["changed"] is False
    assert db_session.get(ExerciseSession, session_id).content_hash == row.content_hash
    assert db_session.scalar(sa.select(sa.func.count()).select_from(SessionMetricVersion)
                             .where(SessionMetricVersion.session_id == session_id)) == 1  # fmt: skip


def test_an_agents_file_filtered_with_other_settings_is_filtered_again_and_todays_is_not(
    client, db_session, db_connection, upload, make_user, auth_headers, object_store
):
    measured, _, _ = simulate("elbow_flexion", 3, seed=2)
    older = sf.encode(make_payload(measured, config=PipelineConfig(sigma_tracked_m=0.03)))
    stale_id, patient, _ = upload(older, "elbow_flexion")
    todays_id, other, _ = upload(make_processed_khs("elbow_flexion", 3, seed=3), "elbow_flexion")
    (job,) = _pipeline_job(client, db_session, db_connection, make_user, auth_headers, patient.id)
    assert job["changed"] is True
    result = db_session.scalar(sa.select(Job.result).where(Job.id == job["id"]))
    assert "sigma_tracked_m 0.03 → 0.0325" in result["refiltered"], result
    after, _ = _file(db_session, object_store, stale_id)
    assert after.params["config"]["sigma_tracked_m"] == 0.0325
    hash_before = db_session.get(ExerciseSession, todays_id).content_hash
    (job,) = _pipeline_job(client, db_session, db_connection, make_user, auth_headers, other.id)
    assert (job["status"], job["changed"]) == ("done", False), "filtered by today's pipeline: left as it is"
    assert db_session.get(ExerciseSession, todays_id).content_hash == hash_before


def test_a_raw_recording_the_pipeline_refuses_fails_the_job_and_leaves_the_session(
    client, db_session, db_connection, upload, make_user, auth_headers, object_store
):
    measured, truth, _ = simulate("squat", 3, seed=9)
    lost = measured.replace(step="test: nothing tracked", positions=np.full_like(measured.positions, np.nan),
                            state=np.zeros_like(measured.state))  # fmt: skip
    data = sf.encode(sf.SessionPayload(session_id=str(uuid.uuid4()), raw=lost, filtered=truth, params={"x": 1},
                                       created_at="2026-11-20T10:00:00Z"))  # fmt: skip
    session_id, patient, _ = upload(data, "squat")
    row = db_session.get(ExerciseSession, session_id)
    before = (row.file_key, row.content_hash, row.status, dict(row.processing_params))
    document = db_session.scalar(sa.select(SessionMetric.document).where(SessionMetric.session_id == session_id))
    (job,) = _pipeline_job(client, db_session, db_connection, make_user, auth_headers, patient.id)
    assert (job["status"], job["attempts"]) == ("failed", 1), "a retry cannot succeed: failed at once"
    assert job["error"].startswith("Today's pipeline cannot filter the session's raw recording"), job["error"]
    assert "no joint is tracked" in job["error"]
    row = db_session.get(ExerciseSession, session_id)
    assert (row.file_key, row.content_hash, row.status, row.processing_params) == before
    assert (
        db_session.scalar(sa.select(SessionMetric.document).where(SessionMetric.session_id == session_id)) == document
    )
    assert db_session.scalar(sa.select(sa.func.count()).select_from(SessionMetricVersion)
                             .where(SessionMetricVersion.session_id == session_id)) == 0  # fmt: skip


def test_earlier_files_go_into_the_archive_and_go_with_an_erasure_or_the_retention_period(
    fetch_archive, client, db_session, db_connection, upload, make_user, auth_headers, object_store
):
    data = make_khs("squat", 2, seed=11)
    session_id, patient, _ = upload(data, "squat")
    old_key = db_session.get(ExerciseSession, session_id).file_key
    _pipeline_job(client, db_session, db_connection, make_user, auth_headers, patient.id)
    new_key = db_session.get(ExerciseSession, session_id).file_key
    admin = auth_headers(make_user("admin"))
    z = zipfile.ZipFile(io.BytesIO(fetch_archive(patient.id, admin).content))
    (session,) = json.loads(z.read("sessions.json"))
    (earlier,) = session["metrics_earlier"]
    assert earlier["file_sha256"] == sf.content_hash(data) and z.read(earlier["file"]) == data
    assert sf.decode(z.read(session["file"])).params["pipeline"] == VERSION
    erased = client.post(f"/api/v1/patients/{patient.id}/erasure", json={"confirm_email": patient.email},
                         headers=admin)  # fmt: skip
    assert erased.status_code == 200, erased.text
    assert erased.json()["rows"]["session_metric_version"] == 1
    assert {old_key, new_key}.isdisjoint(object_store.keys()), "both files of the erased patient are gone"

    kept_id, other, therapist = upload(make_khs("squat", 2, seed=12), "squat")
    kept_old = db_session.get(ExerciseSession, kept_id).file_key
    _pipeline_job(client, db_session, db_connection, make_user, auth_headers, other.id)
    kept_new = db_session.get(ExerciseSession, kept_id).file_key
    db_session.get(ExerciseSession, kept_id).started_at = dt.datetime(2025, 1, 1, tzinfo=dt.UTC)
    apply_retention(db_session=db_session, days=365)
    db_session.commit()
    assert {kept_old, kept_new}.isdisjoint(object_store.keys()), "the retention period removes the earlier file too"
    versions = client.get(f"/api/v1/sessions/{kept_id}/metric-versions", headers=auth_headers(therapist)).json()
    assert [(v["file_kept"], v["file_sha256"] is not None) for v in versions] == [(False, True), (False, True)]
