"""Lock contention reaches clients as 503 DatabaseBusy with Retry-After (the agent retries); other DB errors as 500."""

from __future__ import annotations

import sqlite3

import pytest
from fastapi.testclient import TestClient
from sqlalchemy.exc import OperationalError


class _PgError(Exception):
    def __init__(self, sqlstate: str):
        super().__init__(f"pg error {sqlstate}")
        self.sqlstate = sqlstate


@pytest.mark.parametrize(
    ("orig", "status"),
    [
        (sqlite3.OperationalError("database is locked"), 503),
        (_PgError("40001"), 503),  # serialization_failure
        (_PgError("40P01"), 503),  # deadlock_detected
        (sqlite3.OperationalError("no such table: user"), 500),
    ],
)
def test_database_errors_answer_busy_or_internal(app, orig, status):
    @app.get("/boom")
    def boom():
        raise OperationalError("INSERT ...", {}, orig)

    with TestClient(app, raise_server_exceptions=False) as client:
        response = client.get("/boom")
    assert response.status_code == status
    body = response.json()
    if status == 503:
        assert body["error"] == "DatabaseBusy" and "retry" in body["detail"]
        assert response.headers["retry-after"] == "1"
    else:
        assert body == {"error": "InternalError", "detail": "internal server error"}
