"""Two first uploads of the same session at the same time, on real separate transactions.

Both requests look the session up before either has stored it. On PostgreSQL the unique (patient, client
session id) constraint lets one insert win, and the other answers with the winner's session. SQLite serialises
writers with a database lock: the loser's write fails as "database is locked", which the API answers with
503 DatabaseBusy + Retry-After, and the agent's retry then gets the stored session. Never a duplicate.
"""

from __future__ import annotations

import threading
import time

import pytest
from sqlalchemy import delete, func, select
from sqlalchemy.exc import DBAPIError
from sqlalchemy.orm import Session

from backend.database import is_database_busy
from backend.exercises.models import Exercise
from backend.session_review import service as review
from backend.sessions import service
from backend.sessions.ingest import decode_upload
from backend.sessions.models import ExerciseSession
from backend.users.models import User
from tests.backend.khs_files import make_khs


@pytest.fixture
def committed_patient(engine):
    """A patient committed for real (other transactions see it); deleted with their sessions afterwards."""
    if engine.dialect.name == "sqlite" and engine.url.database in (None, "", ":memory:"):
        pytest.skip("concurrent writers need a database file")
    with Session(engine) as s, s.begin():
        patient = User(email="race-patient@example.org", role="patient", full_name="Race")
        s.add(patient)
        s.flush()
        patient_id = patient.id
    yield patient_id
    with Session(engine) as s, s.begin():
        s.execute(delete(User).where(User.id == patient_id))


def test_simultaneous_first_uploads_store_one_session(engine, committed_patient, monkeypatch):
    upload = decode_upload(make_khs("squat", 2, seed=21), max_frames=10**6, max_decoded_bytes=2**30)
    both_looked = threading.Barrier(2, timeout=30)
    real_find = service.find_session

    waited: set[str] = set()

    def find_together(**kwargs):
        found = real_find(**kwargs)
        name = threading.current_thread().name
        if name.startswith("upload-") and name not in waited:
            waited.add(name)
            both_looked.wait()  # neither request has stored the session yet
        return found

    monkeypatch.setattr(service, "find_session", find_together)
    results: dict[str, tuple[int, bool] | Exception] = {}

    def store() -> tuple[int, bool]:
        with Session(engine, expire_on_commit=False) as s, s.begin():
            exercise = s.scalar(select(Exercise).where(Exercise.slug == "squat"))
            assert exercise is not None
            row, created = review.store_upload(
                db_session=s, upload=upload, patient_id=committed_patient, exercise=exercise, device_id=None
            )
            return row.id, created

    def run(name: str) -> None:
        for attempt in range(2):
            try:
                results[name] = store()
                return
            except DBAPIError as exc:
                results[name] = exc
                if not (engine.dialect.name == "sqlite" and is_database_busy(exc)) or attempt:
                    return
                time.sleep(1)  # 503 DatabaseBusy, Retry-After: 1 - the agent retries
            except Exception as exc:  # noqa: BLE001 - reported by the assertion below
                results[name] = exc
                return

    threads = [threading.Thread(target=run, args=(f"upload-{i}",), name=f"upload-{i}") for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    outcomes = sorted(results.values(), key=lambda r: str(r))
    stored = [r for r in outcomes if isinstance(r, tuple)]
    assert len(stored) == len(outcomes), outcomes
    assert stored[0][0] == stored[1][0], outcomes  # the same stored session
    assert sorted(created for _, created in stored) == [False, True]
    with Session(engine) as s:
        count = s.scalar(
            select(func.count()).select_from(ExerciseSession).where(ExerciseSession.patient_id == committed_patient)
        )
    assert count == 1
