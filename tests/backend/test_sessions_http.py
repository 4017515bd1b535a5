"""The upload size limit over real HTTP (uvicorn): a streamed body is cut off with 413 once over the limit."""

from __future__ import annotations

import httpx
import pytest
from sqlalchemy import func, select

from backend.config import Settings
from backend.sessions.models import ExerciseSession
from tests.kinect_agent._backend import LiveServer

LIMIT = 256 * 1024
CHUNK = 64 * 1024


@pytest.fixture
def settings() -> Settings:
    """Test settings with a 256 KiB upload limit."""
    return Settings(ENVIRONMENT="local", CHECK_MIGRATIONS=False, DATABASE_URL="sqlite://", MAX_UPLOAD_BYTES=LIMIT)


@pytest.fixture
def server(app):
    """The test app served by uvicorn."""
    live = LiveServer(app).start()
    yield live
    live.stop()


def test_chunked_upload_over_the_limit_is_cut_off_with_413(server, db_session, make_user, device_headers):
    patient = make_user("patient")
    _, headers = device_headers(patient)
    db_session.commit()

    def body():
        for _ in range(64):  # 4 MiB offered, 16x the limit, chunked (no Content-Length)
            yield b"\0" * CHUNK

    try:
        response = httpx.post(f"{server.url}/api/v1/sessions", content=body(), headers=headers, timeout=30)
    except httpx.HTTPError as exc:  # the server may close the connection before the client finished sending
        pytest.fail(f"no 413 answer: {exc!r}")
    assert response.status_code == 413, response.text
    assert response.json() == {"error": "SessionTooLarge", "detail": f"the upload exceeds {LIMIT} bytes"}
    count = db_session.scalar(
        select(func.count()).select_from(ExerciseSession).where(ExerciseSession.patient_id == patient.id)
    )
    assert count == 0
