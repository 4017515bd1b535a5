"""`coach-server reanalyze` and `coach-server worker --once` as separate processes, as a clinic runs them."""

from __future__ import annotations

import datetime as dt
import os
import subprocess
import sys
import uuid
from pathlib import Path

import pytest
import sqlalchemy as sa
from sqlalchemy.orm import Session

from backend.exercises.models import Exercise
from backend.exercises.service import sync_exercise_library
from backend.migrate import upgrade
from backend.sessions.metrics import ANALYSIS_VERSION
from backend.sessions.models import ExerciseSession, SessionMetric
from backend.storage.local import LocalStore
from backend.users.models import User
from kinect_agent.formats.session_file import content_hash
from kinect_agent.processing.pipeline import VERSION
from tests.backend.khs_files import make_khs, make_processed_khs

ROOT = Path(__file__).resolve().parents[3]


def _stored_session(fresh_engine, tmp_path, data: bytes) -> tuple[int, dict[str, str]]:
    """Migrates the fresh SQLite database, stores one elbow_flexion session of `data` with a document of no known
    analysis version, and returns (its id, the environment of a coach-server process on them)."""
    url = fresh_engine.url.render_as_string(hide_password=False)
    if not url.startswith("sqlite"):
        pytest.skip("the worker process reaches the fresh database by URL: SQLite file here")
    store = LocalStore(tmp_path / "objects")
    obj = store.put("session", data)
    with fresh_engine.begin() as conn:
        upgrade(conn, "head")
    with Session(fresh_engine) as s, s.begin():
        sync_exercise_library(db_session=s)
        patient = User(email="w@example.org", role="patient")
        s.add(patient)
        s.flush()
        ex = s.scalar(sa.select(Exercise.id).where(Exercise.slug == "elbow_flexion"))
        row = ExerciseSession(client_session_id=uuid.uuid4(), patient_id=patient.id, exercise_id=ex,
                              started_at=dt.datetime.now(dt.UTC), duration_s=10.0, n_frames=300, file_key=obj.key,
                              file_size=obj.size, content_hash=obj.sha256, file_format="khs")  # fmt: skip
        s.add(row)
        s.flush()
        s.add(SessionMetric(session_id=row.id, document={"repetitions": 0, "rom_deg": 1.0}, repetitions=0))
        sid = row.id
    env = os.environ | {"COACH_DATABASE_URL": url, "COACH_STORAGE_DIR": str(tmp_path / "objects"),
                        "PYTHONPATH": str(ROOT)}  # fmt: skip
    return sid, env


def test_reanalyze_then_a_worker_process_updates_the_metrics(fresh_engine, tmp_path):
    sid, env = _stored_session(fresh_engine, tmp_path, make_processed_khs("elbow_flexion", 3, seed=4))
    cli = [sys.executable, "-m", "backend.cli"]
    out = subprocess.run([*cli, "reanalyze"], env=env, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0 and "1 session(s) queued" in out.stdout, out.stderr
    out = subprocess.run([*cli, "worker", "--once"], env=env, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0 and "after 1 job(s)" in out.stderr, out.stderr
    with Session(fresh_engine) as s:
        doc = s.scalar(sa.select(SessionMetric.document).where(SessionMetric.session_id == sid))
        assert doc is not None and doc["analysis_version"] == ANALYSIS_VERSION and doc["repetitions"] >= 2
        assert s.scalar(sa.text("SELECT status FROM job")) == "done"


def test_reanalyze_with_the_pipeline_writes_a_new_file_and_storage_check_sees_both(fresh_engine, tmp_path):
    data = make_khs("elbow_flexion", 3, seed=5)  # filtered by no known pipeline
    sid, env = _stored_session(fresh_engine, tmp_path, data)
    cli = [sys.executable, "-m", "backend.cli"]
    out = subprocess.run([*cli, "reanalyze", "--pipeline"], env=env, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0 and "1 session(s) queued for re-analysis with today's pipeline" in out.stdout, out
    out = subprocess.run([*cli, "worker", "--once"], env=env, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0 and "after 1 job(s)" in out.stderr, out.stderr
    with Session(fresh_engine) as s:
        row = s.get(ExerciseSession, sid)
        assert row is not None
        assert row.content_hash != content_hash(data) and row.processing_params["pipeline"] == VERSION
        assert s.scalar(sa.text("SELECT file_hash FROM session_metric_version")) == content_hash(data)
    out = subprocess.run([*cli, "storage", "check", "--orphans"], env=env, capture_output=True, text=True,
                         timeout=120)  # fmt: skip
    assert out.returncode == 0 and "2 object(s) checked, 0 missing, 0 corrupt, 0 not referenced" in out.stdout, out
    out = subprocess.run([*cli, "reanalyze", "--pipeline"], env=env, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0 and "0 session(s) queued" in out.stdout, "done once: not queued again"
