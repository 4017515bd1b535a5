"""Database admission (backend/db_slots.py): a crowd of simultaneous requests is answered, none starves the pool.

Before it, 60 simultaneous API requests against one server process (pool of 5 + 10 connections) gave 40 × 500 after
the pool's 30 s timeout: threads waited for connections held by requests that waited for threads.
"""

from __future__ import annotations

import asyncio
from collections import Counter
from collections.abc import Iterator

import httpx
import pytest
from sqlalchemy import create_engine
from sqlalchemy.engine import Engine
from sqlalchemy.orm import Session

from backend.database import db_dependency, get_db, make_engine, utcnow
from backend.db_slots import DbSlots, pool_capacity
from backend.devices.models import Device
from backend.exceptions import ServerBusy
from backend.exercises.service import sync_exercise_library
from backend.main import create_app
from backend.migrate import upgrade
from backend.patients.models import TherapistPatient
from backend.security import DEVICE_TOKEN_PREFIX, new_token, token_hash
from backend.users.service import create_api_token, create_user
from tests.backend.khs_files import make_khs
from tests.kinect_agent._backend import LiveServer

CROWD = 80  # more than the 40 worker threads plus the 15 pooled connections


def test_pool_capacity_is_size_plus_overflow(fresh_engine) -> None:
    assert pool_capacity(fresh_engine) == 15  # SQLAlchemy's QueuePool defaults, on SQLite files and PostgreSQL alike
    assert pool_capacity(create_engine("sqlite://")) is None  # one shared in-memory connection: no limit


def test_a_request_that_waits_too_long_is_told_the_server_is_busy(fresh_engine) -> None:
    slots = DbSlots(lambda: fresh_engine, wait_s=0.05)

    async def crowd() -> list[str]:
        assert slots.capacity is not None
        held = [await slots.acquire() for _ in range(slots.capacity)]
        try:
            await slots.acquire()
        except ServerBusy as exc:
            return [exc.message]
        finally:
            for release in held:
                release()
        return []

    assert asyncio.run(crowd()) == ["no database connection came free within 0.05 s; retry in a few seconds"]


@pytest.fixture
def crowd_engine(fresh_engine, tmp_path) -> Engine:
    """An empty database with the server's own engine (on SQLite the suite's engine begins every transaction at
    once, for its rolled-back test transactions, which makes concurrent readers that write fail as locked)."""
    if fresh_engine.dialect.name == "postgresql":
        return fresh_engine
    return make_engine(f"sqlite:///{tmp_path / 'crowd.db'}")


@pytest.fixture
def crowd_server(crowd_engine, settings) -> Iterator[tuple[str, dict[str, str]]]:
    """The app on a migrated database of its own with the real pool, served by uvicorn; yields (url, headers)."""
    with crowd_engine.begin() as conn:
        upgrade(conn)
    with Session(crowd_engine, expire_on_commit=False) as s:
        therapist = create_user(db_session=s, email="crowd@example.org", password=None, role="therapist")
        _, token = create_api_token(db_session=s, user=therapist, name="t", scopes=["read", "write"], days=1)
        s.commit()
    app = create_app(settings, engine=crowd_engine)
    app.dependency_overrides[get_db] = db_dependency(crowd_engine)
    server = LiveServer(app).start()
    try:
        yield server.url, {"Authorization": f"Bearer {token}"}
    finally:
        server.stop()


def test_a_crowd_of_simultaneous_requests_is_answered(crowd_server) -> None:
    url, headers = crowd_server

    async def crowd() -> Counter[int]:
        async with httpx.AsyncClient(base_url=url, headers=headers, timeout=60,
                                     limits=httpx.Limits(max_connections=CROWD)) as client:  # fmt: skip
            answers = await asyncio.gather(
                *(client.get("/api/v1/patients" if i % 2 else "/api/v1/dashboard") for i in range(CROWD))
            )
        return Counter(a.status_code for a in answers)

    assert asyncio.run(crowd()) == Counter({200: CROWD})


@pytest.fixture
def one_slot_server(tmp_path, settings) -> Iterator[tuple[str, dict[str, str], dict[str, str]]]:
    """The app with ONE pooled connection (so one database slot) on a SQLite file of its own, served by uvicorn;
    yields (url, a therapist's headers, a paired device's headers). The admission, not the database, is under test,
    so it is SQLite on both of the suite's runs."""
    engine = create_engine(f"sqlite:///{tmp_path / 'one.db'}", pool_size=1, max_overflow=0,
                           connect_args={"check_same_thread": False, "timeout": 15})  # fmt: skip
    with engine.begin() as conn:
        upgrade(conn)
    with Session(engine, expire_on_commit=False) as s:
        therapist = create_user(db_session=s, email="t@example.org", password=None, role="therapist")
        patient = create_user(db_session=s, email="p@example.org", password=None, role="patient")
        s.add(TherapistPatient(therapist_id=therapist.id, patient_id=patient.id, created_at=utcnow()))
        _, token = create_api_token(db_session=s, user=therapist, name="t", scopes=["read", "write"], days=1)
        device_token = new_token(DEVICE_TOKEN_PREFIX)
        s.add(Device(patient_id=patient.id, name="home", token_hash=token_hash(device_token)))
        sync_exercise_library(db_session=s)
        s.commit()
    app = create_app(settings.model_copy(update={"DB_SLOT_WAIT_S": 3.0}), engine=engine)
    app.dependency_overrides[get_db] = db_dependency(engine)
    server = LiveServer(app).start()
    try:
        yield server.url, {"Authorization": f"Bearer {token}"}, {"Authorization": f"Bearer {device_token}"}
    finally:
        server.stop()
        engine.dispose()


def test_a_slow_upload_does_not_hold_the_database_while_its_body_comes_in(one_slot_server) -> None:
    """A patient's upload over a slow uplink: while its body trickles in, the one database slot serves others; the
    upload is stored when the rest arrives. Without giving the slot back, the therapist's request waited for the
    upload and got 503 ServerBusy after COACH_DB_SLOT_WAIT_S."""
    url, therapist, device = one_slot_server
    data = make_khs("squat", 3, seed=4)

    async def scenario() -> tuple[int, int]:
        answered = asyncio.Event()

        async def trickle():
            yield data[: len(data) // 2]
            await asyncio.sleep(1.0)  # the server has checked the device's token and reads the body
            await asyncio.wait_for(answered.wait(), timeout=15)  # the rest only once the therapist was answered
            yield data[len(data) // 2 :]

        async with httpx.AsyncClient(base_url=url, timeout=60) as client:
            headers = {**device, "Content-Type": "application/octet-stream"}
            upload = asyncio.create_task(client.post("/api/v1/sessions", content=trickle(), headers=headers))
            await asyncio.sleep(1.5)
            listed = await client.get("/api/v1/patients", headers=therapist)
            answered.set()
            return listed.status_code, (await upload).status_code

    assert asyncio.run(scenario()) == (200, 201)
