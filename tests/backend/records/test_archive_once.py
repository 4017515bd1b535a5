"""The admin's `coach-server patient-data archive` and a worker on the archive of the same data at the same moment:
it is built and stored once (one object in the store, one patient_archive row), and the command writes that archive.
Committed data on real connections (the worker in a thread of its own, the command in the test's), cleaned up after;
on SQLite and PostgreSQL, with each object store."""

from __future__ import annotations

import datetime as dt
import threading
import time
import uuid
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import pytest
import sqlalchemy as sa
from sqlalchemy.orm import Session, sessionmaker

from backend.audit.models import AuditEvent
from backend.cli import build_parser
from backend.exercises.models import Exercise
from backend.jobs.models import Job
from backend.jobs.worker import work
from backend.records import commands, prepared_archive
from backend.records.models import PatientArchive
from backend.sessions.models import ExerciseSession
from backend.storage import get_store
from backend.users.models import User

SESSIONS = 8  # of 1 MiB of random bytes each: a build of about a second, long enough for the two to overlap


@dataclass(frozen=True)
class Committed:
    """A patient with stored sessions and an admin, committed: the sessions' factory and who they are."""

    factory: sessionmaker[Session]
    patient_id: int
    admin_email: str


@pytest.fixture
def committed(engine, with_store) -> Iterator[Committed]:
    """An admin and a patient with SESSIONS stored session files in the test's store, committed; deleted after."""
    factory = sessionmaker(bind=engine, expire_on_commit=False)
    tag, rng = uuid.uuid4().hex[:8], np.random.default_rng(20261128)
    with factory() as db:
        admin = User(email=f"admin-once-{tag}@example.org", role="admin")
        patient = User(email=f"patient-once-{tag}@example.org", role="patient")
        db.add_all([admin, patient])
        db.flush()
        exercise = db.scalar(sa.select(Exercise).order_by(Exercise.slug).limit(1))
        assert exercise is not None, "the run's database has the exercise library"
        for k in range(SESSIONS):
            obj = get_store().put("session", rng.bytes(2**20))
            db.add(ExerciseSession(client_session_id=uuid.uuid4(), patient_id=patient.id, exercise_id=exercise.id,
                                   started_at=dt.datetime(2026, 11, 1 + k, tzinfo=dt.UTC), duration_s=30.0,
                                   n_frames=900, file_key=obj.key, file_size=obj.size, content_hash=obj.sha256,
                                   file_format="khs"))  # fmt: skip
        db.commit()
        ids = [admin.id, patient.id]
    yield Committed(factory, patient.id, admin.email)
    with factory() as db:
        db.execute(sa.delete(Job).where(Job.key.like(f"archive:{patient.id}:%")))
        db.execute(sa.delete(AuditEvent).where(AuditEvent.patient_id == patient.id))
        db.execute(sa.delete(User).where(User.id.in_(ids)))  # cascades to sessions and the archive's row
        db.commit()


def _archive_keys(store) -> list[str]:
    return sorted(k for k in store.keys() if k.startswith("archive/"))


def _building(factory: sessionmaker[Session], patient_id: int, timeout_s: float = 60.0) -> None:
    """Waits until the worker is inside the build: its job running with its first progress report written."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        with factory() as db:
            job = db.scalar(sa.select(Job).where(Job.key.like(f"archive:{patient_id}:%")))
            if job is not None and job.status == "running" and (job.result or {}).get("progress"):
                return
        time.sleep(0.02)
    raise AssertionError(f"the worker did not start the build within {timeout_s} s")


def test_the_command_and_a_worker_on_the_same_data_store_one_archive(committed, with_store, settings, tmp_path):
    factory, pid = committed.factory, committed.patient_id
    with factory() as db:  # the patient asked on the page: the job is queued
        asked = prepared_archive.ask_archive(db_session=db, patient=db.get(User, pid), requested_by="the patient")
        db.commit()
    assert asked.state == "preparing"
    ran: list[int] = []
    errors: list[BaseException] = []

    def worker() -> None:
        try:
            ran.append(work(sessionmaker=factory, settings=settings, name="test-worker", once=True,
                            kinds=("archive",)))  # fmt: skip
        except BaseException as exc:  # noqa: BLE001 - reported below
            errors.append(exc)

    thread = threading.Thread(target=worker)
    thread.start()
    try:
        _building(factory, pid)  # the worker is building it when the admin runs the command
        out = tmp_path / "archive.zip"
        args = build_parser().parse_args(["patient-data", "archive", str(pid), "--admin", committed.admin_email,
                                          "--out", str(out)])  # fmt: skip
        with factory() as db:
            said = commands.run(args, db)
            db.commit()
    finally:
        thread.join(timeout=120)
    assert not errors, errors
    assert ran == [1], "the worker ran the job"
    with factory() as db:
        rows = db.scalars(sa.select(PatientArchive).where(PatientArchive.patient_id == pid)).all()
        jobs = db.scalars(sa.select(Job).where(Job.key.like(f"archive:{pid}:%"))).all()
    assert len(rows) == 1 and rows[0].sessions == SESSIONS
    assert _archive_keys(with_store) == [rows[0].data_key], "one archive stored, the one the row names"
    assert [(j.status, j.attempts) for j in jobs] == [("done", 1)], "one job, run once"
    assert out.read_bytes() == with_store.get(rows[0].data_key, rows[0].data_hash), said
    assert "made now" in said, said
