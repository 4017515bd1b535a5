"""Re-analysis on the job queue: idempotent jobs, old metrics kept beside new, a crashed worker's job taken again,
failures retried then recorded."""

from __future__ import annotations

import datetime as dt

import sqlalchemy as sa
from sqlalchemy.orm import Session

from backend.config import Settings
from backend.database import utcnow
from backend.jobs import queue
from backend.jobs.models import Job, SessionMetricVersion
from backend.jobs.worker import work
from backend.records.reanalysis import enqueue_reanalysis
from backend.sessions.metrics import ANALYSIS_VERSION
from backend.sessions.models import ExerciseSession, SessionMetric
from tests.backend.khs_files import make_processed_khs

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
