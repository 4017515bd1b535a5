"""Server test fixtures: one migrated database per run, one rolled-back transaction per test, factories.

COACH_TEST_DATABASE_URL picks the database (default: a SQLite file in a temp dir). On PostgreSQL the run uses
its own schema coach_test_<pid> (dropped and recreated at start, dropped at the end), so reruns and parallel
runs start empty.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator

import pytest
from argon2 import PasswordHasher
from fastapi.testclient import TestClient
from sqlalchemy import create_engine, event, select, text
from sqlalchemy.engine import Connection, Engine
from sqlalchemy.orm import Session

from backend import security
from backend.config import Settings, get_settings
from backend.database import get_db, import_all_models, make_engine, request_session, utcnow
from backend.devices.models import Device
from backend.exercises.models import Exercise
from backend.main import create_app
from backend.migrate import upgrade
from backend.patients.models import TherapistPatient
from backend.security import DEVICE_TOKEN_PREFIX, new_token, token_hash
from backend.users.models import User
from backend.users.service import create_api_token

import_all_models()

PASSWORD = "correct horse battery"
# argon2id at its cheapest (1 pass over 1 MiB, one lane: under 1 ms of CPU instead of about 0.25 s): the same code
# path and hash format as the product's, for a suite that hashes and checks hundreds of passwords (Django's test
# settings pick a fast hasher the same way). tests/backend/test_security.py holds the product's own hasher to the
# library's recommended parameters.
TEST_PASSWORD_HASHER = PasswordHasher(time_cost=1, memory_cost=1024, parallelism=1)


@pytest.fixture(scope="session", autouse=True)
def fast_password_hashing() -> Iterator[None]:
    """Makes backend.security hash and check passwords with TEST_PASSWORD_HASHER for the run (its dummy hash too, so
    that a login without a user costs what one with a user does); tests/frontend/conftest.py imports it for the demo
    clinic it seeds."""
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(security, "PASSWORD_HASHER", TEST_PASSWORD_HASHER)
        patch.setattr(security, "DUMMY_HASH", TEST_PASSWORD_HASHER.hash("not-a-real-password"))
        yield


def _pg_engine(url: str, schema: str) -> Engine:
    return create_engine(url, connect_args={"options": f"-csearch_path={schema}"})


def build_engine(url: str, name: str) -> tuple[Engine, Callable[[], None]]:
    """Returns (engine on an empty database or schema, cleanup callable) for a test database URL."""
    if url.startswith("postgresql"):
        schema = f"{name}_{os.getpid()}"
        admin = create_engine(url, isolation_level="AUTOCOMMIT")
        with admin.connect() as conn:
            conn.execute(text(f'DROP SCHEMA IF EXISTS "{schema}" CASCADE'))
            conn.execute(text(f'CREATE SCHEMA "{schema}"'))
        engine = _pg_engine(url, schema)

        def cleanup() -> None:
            engine.dispose()
            with admin.connect() as conn:
                conn.execute(text(f'DROP SCHEMA IF EXISTS "{schema}" CASCADE'))
            admin.dispose()

        return engine, cleanup
    engine = make_engine(url)
    _sqlite_real_transactions(engine)
    return engine, engine.dispose


def _sqlite_real_transactions(engine: Engine) -> None:
    """Makes pysqlite emit BEGIN itself, so SAVEPOINTs nest inside the test transaction (SQLAlchemy recipe)."""

    @event.listens_for(engine, "connect")
    def _no_implicit(dbapi_connection, _record) -> None:
        dbapi_connection.isolation_level = None

    @event.listens_for(engine, "begin")
    def _begin(conn) -> None:
        conn.exec_driver_sql("BEGIN")


@pytest.fixture(scope="session")
def test_database_url(tmp_path_factory) -> str:
    """The database URL of this run (COACH_TEST_DATABASE_URL or a fresh SQLite file)."""
    url = os.environ.get("COACH_TEST_DATABASE_URL")
    return url or f"sqlite:///{tmp_path_factory.mktemp('db') / 'test.db'}"


@pytest.fixture(scope="session")
def engine(test_database_url) -> Iterator[Engine]:
    """An engine on a database migrated to head once per run, with the exercise library synced."""
    eng, cleanup = build_engine(test_database_url, "coach_test")
    with eng.begin() as conn:
        upgrade(conn, "head")
    try:
        from backend.exercises.service import sync_exercise_library

        with Session(eng) as session, session.begin():
            sync_exercise_library(db_session=session)
    except ModuleNotFoundError as exc:
        if exc.name != "backend.exercises.library":
            raise
    yield eng
    cleanup()


@pytest.fixture
def fresh_engine(test_database_url, tmp_path) -> Iterator[Engine]:
    """An engine on an EMPTY extra database (SQLite file or PostgreSQL schema) for migration tests."""
    url = test_database_url
    if not url.startswith("postgresql"):
        url = f"sqlite:///{tmp_path / 'fresh.db'}"
    eng, cleanup = build_engine(url, "coach_fresh")
    yield eng
    cleanup()


@pytest.fixture
def db_connection(engine) -> Iterator[Connection]:
    """A connection inside an outer transaction that is rolled back after the test."""
    conn = engine.connect()
    trans = conn.begin()
    yield conn
    trans.rollback()
    conn.close()


@pytest.fixture
def db_session(db_connection) -> Iterator[Session]:
    """A session joined to the test transaction; its commits only release SAVEPOINTs."""
    session = Session(bind=db_connection, join_transaction_mode="create_savepoint", expire_on_commit=False)
    yield session
    session.close()


@pytest.fixture
def settings() -> Settings:
    """Settings of the test app (local environment, migration check off: the test DB is migrated)."""
    # event streams end at once: the test client reads a response to its end
    return Settings(
        ENVIRONMENT="local",
        CHECK_MIGRATIONS=False,
        DATABASE_URL="sqlite://",
        EVENTS_STREAM_MAX_S=0.0,
        LIVE_OFFLINE_GRACE_S=0.0,
        LIVE_WARM_UP=False,  # tests/backend/camera/test_camera_warm_up.py turns it on
    )


def make_test_app(db_session: Session, settings: Settings):
    """Returns an app whose requests use db_session (commit on success, roll back on error, like get_db)."""
    app = create_app(settings)

    def override_db() -> Iterator[Session]:
        yield from request_session(db_session)

    app.dependency_overrides[get_db] = override_db
    app.dependency_overrides[get_settings] = lambda: settings
    return app


@pytest.fixture
def app(db_session, settings):
    """The ASGI app bound to the test session."""
    return make_test_app(db_session, settings)


@pytest.fixture
def run_jobs(db_session, db_connection, settings):
    """Callable: commits the test's session, then a real worker (backend.jobs.worker.work) runs every due job on
    the test's connection until none is left; returns how many it ran."""
    from backend.jobs.worker import work

    def run() -> int:
        db_session.commit()
        sessions = lambda: Session(bind=db_connection, join_transaction_mode="create_savepoint",  # noqa: E731
                                   expire_on_commit=False)  # fmt: skip
        ran = work(sessionmaker=sessions, settings=settings, name="test-worker", once=True)
        db_session.expire_all()
        return ran

    return run


@pytest.fixture
def fetch_archive(client, run_jobs):
    """Callable: fetch_archive(patient_id, headers) -> the GET /patients/{id}/archive response once a worker made the
    archive the first ask queued (a 202, then run_jobs, then the download)."""

    def fetch(patient_id: int, headers: dict[str, str]):
        response = client.get(f"/api/v1/patients/{patient_id}/archive", headers=headers)
        if response.status_code == 202:
            run_jobs()
            response = client.get(f"/api/v1/patients/{patient_id}/archive", headers=headers)
        assert response.status_code == 200, response.text
        return response

    return fetch


@pytest.fixture
def client(app) -> Iterator[TestClient]:
    """An httpx-based client of the ASGI app (no lifespan: the migration check is tested separately)."""
    with TestClient(app, raise_server_exceptions=False) as c:
        yield c


@pytest.fixture
def make_user(db_session):
    """Factory: make_user(role='patient', email=None, password=None, full_name='') -> User (flushed)."""
    counter = iter(range(1, 10**6))

    def make(role: str = "patient", email: str | None = None, password: str | None = None, full_name: str = ""):
        from backend.users.service import create_user

        email = email or f"{role}{next(counter)}-{os.getpid()}@example.org"
        return create_user(db_session=db_session, email=email, password=password, role=role, full_name=full_name)

    return make


@pytest.fixture
def make_patient_with_therapist(db_session, make_user):
    """Factory: returns (patient, therapist) with the therapist assigned to the patient."""

    def make() -> tuple[User, User]:
        patient, therapist = make_user("patient"), make_user("therapist")
        db_session.add(TherapistPatient(therapist_id=therapist.id, patient_id=patient.id, created_at=utcnow()))
        db_session.flush()
        return patient, therapist

    return make


@pytest.fixture
def auth_headers(db_session):
    """Factory: auth_headers(user, scopes=('read', 'write')) -> {'Authorization': 'Bearer khc_...'}."""

    def make(user: User, scopes=("read", "write")) -> dict[str, str]:
        _, token = create_api_token(db_session=db_session, user=user, name="test", scopes=list(scopes), days=365)
        return {"Authorization": f"Bearer {token}"}

    return make


@pytest.fixture
def device_headers(db_session):
    """Factory: device_headers(patient) -> (Device, {'Authorization': 'Bearer khd_...'})."""

    def make(patient: User) -> tuple[Device, dict[str, str]]:
        token = new_token(DEVICE_TOKEN_PREFIX)
        device = Device(patient_id=patient.id, name="test device", token_hash=token_hash(token))
        db_session.add(device)
        db_session.flush()
        return device, {"Authorization": f"Bearer {token}"}

    return make


@pytest.fixture
def exercise(db_session) -> Exercise:
    """An exercise of the library (the first by slug; a test row when the library is not installed yet)."""
    row = db_session.scalar(select(Exercise).order_by(Exercise.slug).limit(1))
    if row is None:
        row = Exercise(
            slug="test_squat",
            name="Test squat",
            instructions="Squat.",
            defining_angles=["knee_flexion_left"],
            plane="sagittal",
            normal_range_min_deg=0.0,
            normal_range_max_deg=120.0,
            pose="standing",
        )
        db_session.add(row)
        db_session.flush()
    return row


@pytest.fixture
def other_exercise(db_session, exercise) -> Exercise:
    """A second exercise of the library."""
    return db_session.scalar(select(Exercise).where(Exercise.id != exercise.id).order_by(Exercise.slug).limit(1))


@pytest.fixture
def store(db_session):
    """Factory: store(patient, exercise, started_at, **kw) -> ExerciseSession (see session_rows.store_session)."""
    from tests.backend.session_rows import store_session

    return lambda *args, **kw: store_session(db_session, *args, **kw)


@pytest.fixture
def upload(client, make_patient_with_therapist, auth_headers, run_jobs):
    """Factory: upload(data, exercise) -> (session id, patient, therapist) after a real upload by the patient and a
    worker's run of the job it queued (the session page's detail, backend.sessions.prepared)."""

    def send(data: bytes, exercise: str):
        patient, therapist = make_patient_with_therapist()
        headers = {"Content-Type": "application/octet-stream", **auth_headers(patient)}
        response = client.post("/api/v1/sessions", content=data, headers=headers, params={"exercise": exercise})
        assert response.status_code == 201, response.text
        assert run_jobs() == 1, "an upload queues the build of its detail"
        return response.json()["id"], patient, therapist

    return send


# ---------------------------------------------------------------------------------------------- object store
# COACH_TEST_STORAGE=s3 runs the server tests with session files and replays in S3 (moto's server mode);
# the default is the local filesystem store in a temporary folder.


@pytest.fixture(scope="session")
def _s3_endpoint():
    from tests.backend.object_stores import s3_server

    with s3_server() as endpoint:
        yield endpoint


@pytest.fixture(scope="session", autouse=True)
def object_store(tmp_path_factory, request):
    """The object store of this test run (backend.storage.use_store), local or S3 by COACH_TEST_STORAGE."""
    from backend.storage import use_store
    from backend.storage.base import ObjectStore
    from tests.backend.object_stores import local_store, s3_store

    kind = os.environ.get("COACH_TEST_STORAGE", "local")
    store: ObjectStore
    if kind == "s3":
        store = s3_store(request.getfixturevalue("_s3_endpoint"))
    else:
        store = local_store(tmp_path_factory.mktemp("objects"))
    use_store(store)
    yield store
    use_store(None)
