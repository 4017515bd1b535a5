"""Database plumbing: declarative Base with a naming convention, UTC timestamps, engine and session factory."""

from __future__ import annotations

import datetime as dt
from collections.abc import Callable, Iterator
from functools import lru_cache
from typing import Any, TypeVar

from sqlalchemy import DateTime, MetaData, create_engine, event, select
from sqlalchemy.engine import Dialect, Engine
from sqlalchemy.engine.interfaces import DBAPIConnection
from sqlalchemy.exc import DBAPIError, IntegrityError
from sqlalchemy.orm import DeclarativeBase, Session, sessionmaker
from sqlalchemy.types import TypeDecorator

NAMING_CONVENTION = {
    "ix": "ix_%(column_0_label)s",
    "uq": "uq_%(table_name)s_%(column_0_N_name)s",
    "ck": "ck_%(table_name)s_%(constraint_name)s",
    "fk": "fk_%(table_name)s_%(column_0_name)s_%(referred_table_name)s",
    "pk": "pk_%(table_name)s",
}


def utcnow() -> dt.datetime:
    """Returns the current time as a timezone-aware UTC datetime."""
    return dt.datetime.now(dt.UTC)


class UTCDateTime(TypeDecorator[dt.datetime]):
    """Stores timezone-aware datetimes as UTC and always returns them timezone-aware (SQLite drops the zone)."""

    impl = DateTime(timezone=True)
    cache_ok = True

    def process_bind_param(self, value: dt.datetime | None, dialect: Dialect) -> dt.datetime | None:
        if value is None:
            return None
        if value.tzinfo is None:
            raise ValueError("naive datetime given; use timezone-aware UTC datetimes")
        value = value.astimezone(dt.UTC)
        return value.replace(tzinfo=None) if dialect.name == "sqlite" else value

    def process_result_value(self, value: dt.datetime | None, dialect: Dialect) -> dt.datetime | None:
        if value is None:
            return None
        return value.replace(tzinfo=dt.UTC) if value.tzinfo is None else value.astimezone(dt.UTC)


class Base(DeclarativeBase):
    """Declarative base of every table; timestamps map to UTCDateTime."""

    metadata = MetaData(naming_convention=NAMING_CONVENTION)
    type_annotation_map = {dt.datetime: UTCDateTime}


def _sqlite_pragmas(dbapi_connection: DBAPIConnection, _record: object) -> None:
    """Foreign keys on; write-ahead log so readers never block the one writer (and the writer not the readers)."""
    cursor = dbapi_connection.cursor()
    cursor.execute("PRAGMA foreign_keys=ON")
    cursor.execute("PRAGMA journal_mode=WAL")
    cursor.close()


Row = TypeVar("Row", bound=Base)


def keep_row(db_session: Session, model: type[Row], key: dict[str, Any], fields: dict[str, Any]) -> None:
    """Sets `fields` on the row of `model` whose unique columns are `key`, inserting it when there is none, in a
    savepoint; when another worker inserts the same key first (IntegrityError), its row stays: workers store the
    same result for the same key (replays, session details, downloads)."""
    try:
        with db_session.begin_nested():
            row = db_session.scalar(select(model).filter_by(**key))
            if row is None:
                db_session.add(model(**key, **fields))
            else:
                for name, value in fields.items():
                    setattr(row, name, value)
    except IntegrityError:
        pass


def make_engine(url: str) -> Engine:
    """Returns an engine for a database URL (SQLite gets foreign keys on and its parent folder created)."""
    if url.startswith("sqlite"):
        from pathlib import Path

        from sqlalchemy.engine import make_url

        database = make_url(url).database
        if database and database != ":memory:":
            Path(database).parent.mkdir(parents=True, exist_ok=True)
        # timeout: a writer waits up to 15 s for another writer's lock before SQLite answers "database is locked"
        engine = create_engine(url, connect_args={"check_same_thread": False, "timeout": 15})
        event.listen(engine, "connect", _sqlite_pragmas)
        return engine
    return create_engine(url, pool_pre_ping=True)


@lru_cache
def get_engine(url: str | None = None) -> Engine:
    """Returns the process-wide engine for the configured (or given) database URL."""
    from backend.config import get_settings

    return make_engine(url or get_settings().DATABASE_URL)


@lru_cache
def get_sessionmaker(url: str | None = None) -> sessionmaker[Session]:
    """Returns the session factory bound to get_engine(url)."""
    return sessionmaker(bind=get_engine(url), expire_on_commit=False)


def request_session(session: Session) -> Iterator[Session]:
    """Yields session for one request; commits on success, rolls back on error (unless error.keep_changes)."""
    try:
        yield session
    except BaseException as exc:
        if getattr(exc, "keep_changes", False):
            session.commit()
        else:
            session.rollback()
        raise
    else:
        session.commit()


def _session_from(factory: sessionmaker[Session]) -> Iterator[Session]:
    session = factory()
    try:
        yield from request_session(session)
    finally:
        session.close()


def get_db() -> Iterator[Session]:
    """Yields one session per request; commits on success and rolls back on any error."""
    yield from _session_from(get_sessionmaker())


def db_dependency(engine: Engine) -> Callable[[], Iterator[Session]]:
    """Returns a dependency like get_db on another engine (benchmarks and tests serving their own database:
    app.dependency_overrides[get_db] = db_dependency(engine))."""
    factory = sessionmaker(bind=engine, expire_on_commit=False)

    def db() -> Iterator[Session]:
        yield from _session_from(factory)

    return db


def import_all_models() -> None:
    """Imports every model module so Base.metadata knows every table (used by Alembic and tests)."""
    import backend.audit.models  # noqa: F401
    import backend.camera.models  # noqa: F401
    import backend.devices.models  # noqa: F401
    import backend.exercises.models  # noqa: F401
    import backend.feeling.models  # noqa: F401
    import backend.jobs.models  # noqa: F401
    import backend.patients.models  # noqa: F401
    import backend.plans.models  # noqa: F401
    import backend.records.models  # noqa: F401
    import backend.reminders.models  # noqa: F401
    import backend.replay.models  # noqa: F401
    import backend.replies.models  # noqa: F401
    import backend.sessions.models  # noqa: F401
    import backend.suggestions.models  # noqa: F401
    import backend.users.models  # noqa: F401
    import backend.voice.models  # noqa: F401


def is_database_busy(exc: DBAPIError) -> bool:
    """True for lock contention a retry resolves: SQLite "database is locked", PostgreSQL serialisation/deadlock."""
    pgcode = getattr(exc.orig, "sqlstate", None) or getattr(exc.orig, "pgcode", None)
    return pgcode in {"40001", "40P01"} or "database is locked" in str(exc.orig)
