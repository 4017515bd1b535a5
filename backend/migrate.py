"""Alembic, programmatically: upgrade/downgrade a database and check that it is at head."""

from __future__ import annotations

from pathlib import Path

from alembic import command
from alembic.config import Config
from alembic.runtime.migration import MigrationContext
from alembic.script import ScriptDirectory
from sqlalchemy.engine import Connection, Engine

from backend.exceptions import DatabaseNotMigrated

ALEMBIC_INI = Path(__file__).resolve().parent.parent / "migrations" / "alembic.ini"


def alembic_config(connection: Connection | None = None, url: str | None = None) -> Config:
    """Returns the Alembic config of migrations/, bound to a connection or URL when given."""
    cfg = Config(str(ALEMBIC_INI))
    if connection is not None:
        cfg.attributes["connection"] = connection
    if url is not None:
        cfg.set_main_option("sqlalchemy.url", url.replace("%", "%%"))
    return cfg


def head_revision() -> str:
    """Returns the newest revision id in migrations/versions."""
    head = ScriptDirectory.from_config(alembic_config()).get_current_head()
    assert head is not None
    return head


def current_revision(connection: Connection) -> str | None:
    """Returns the revision the database is at (None when never migrated)."""
    return MigrationContext.configure(connection).get_current_revision()


def upgrade(connection: Connection, revision: str = "head") -> None:
    """Upgrades the database on this connection to revision."""
    command.upgrade(alembic_config(connection), revision)


def downgrade(connection: Connection, revision: str) -> None:
    """Downgrades the database on this connection to revision ('base' = empty)."""
    command.downgrade(alembic_config(connection), revision)


def check_at_head(engine: Engine) -> None:
    """Raises DatabaseNotMigrated unless the database is at Alembic head."""
    with engine.connect() as conn:
        current = current_revision(conn)
    head = head_revision()
    if current != head:
        raise DatabaseNotMigrated(
            f"database is at revision {current or 'none (empty)'} but the code needs {head}; "
            "run `coach-server migrate` first"
        )
