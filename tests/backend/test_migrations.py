"""Migrations run up and down, match the models, and the server refuses a database behind head."""

from __future__ import annotations

import pytest
from alembic.autogenerate import compare_metadata
from alembic.runtime.migration import MigrationContext
from fastapi.testclient import TestClient
from sqlalchemy import inspect

from backend.config import Settings
from backend.database import Base
from backend.exceptions import DatabaseNotMigrated
from backend.main import create_app
from backend.migrate import check_at_head, current_revision, downgrade, head_revision, upgrade


def test_upgrade_matches_models_then_downgrade_empties(fresh_engine):
    with fresh_engine.begin() as conn:
        upgrade(conn, "head")
    with fresh_engine.connect() as conn:
        assert current_revision(conn) == head_revision()
        diff = compare_metadata(MigrationContext.configure(conn), Base.metadata)
        assert diff == [], f"models and migrations differ: {diff}"
    with fresh_engine.begin() as conn:
        downgrade(conn, "base")
    with fresh_engine.connect() as conn:
        assert set(inspect(conn).get_table_names()) <= {"alembic_version"}
        assert current_revision(conn) is None
    with fresh_engine.begin() as conn:
        upgrade(conn, "head")
    with fresh_engine.connect() as conn:
        assert "exercise_session" in inspect(conn).get_table_names()


def test_server_refuses_to_start_behind_head(fresh_engine):
    app = create_app(Settings(CHECK_MIGRATIONS=True), engine=fresh_engine)
    with pytest.raises(DatabaseNotMigrated, match="run `coach-server migrate`"):
        with TestClient(app):
            pass


def test_server_starts_at_head(fresh_engine):
    with fresh_engine.begin() as conn:
        upgrade(conn, "head")
    check_at_head(fresh_engine)
    app = create_app(Settings(CHECK_MIGRATIONS=True), engine=fresh_engine)
    with TestClient(app) as client:
        assert client.get("/api/v1/version").json()["database_revision"] == head_revision()
