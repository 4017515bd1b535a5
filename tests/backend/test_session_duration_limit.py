"""A recording longer than COACH_SESSION_MAX_DURATION_S (two hours by default) is refused at upload: no home session
lasts 60 hours, and with the frame limit this bounds the work one accepted file can cause."""

from __future__ import annotations

import pytest

from backend.config import Settings
from kinect_agent.formats import session_file as sf
from tests.backend.khs_files import make_khs

LIMIT_S = 5.0


@pytest.fixture
def settings() -> Settings:
    """The suite's test settings with a 5-second session limit."""
    return Settings(ENVIRONMENT="local", CHECK_MIGRATIONS=False, DATABASE_URL="sqlite://", EVENTS_STREAM_MAX_S=0.0,
                    LIVE_OFFLINE_GRACE_S=0.0, SESSION_MAX_DURATION_S=LIMIT_S)  # fmt: skip


def test_a_recording_longer_than_the_limit_is_refused(client, make_user, device_headers, db_session):
    data = make_khs("squat", 3, seed=2)
    duration = sf.decode(data).raw.duration
    assert duration > LIMIT_S
    _, headers = device_headers(make_user("patient"))
    db_session.commit()
    response = client.post("/api/v1/sessions", content=data, params={"exercise": "squat"},
                           headers=headers | {"Content-Type": "application/octet-stream"})  # fmt: skip
    assert response.status_code == 400, response.text
    assert response.json()["detail"].startswith(f"too_long: the recording lasts {duration:.0f} s"), response.json()


def test_the_default_limit_is_two_hours():
    assert Settings.model_fields["SESSION_MAX_DURATION_S"].default == 7200.0
