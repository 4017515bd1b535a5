"""Uploading the queue to the real coaching server: idempotent, retried, never losing or doubling a session."""

from __future__ import annotations

import random

import httpx
import pytest
from sqlalchemy import func, select

from kinect_agent.capture import make_payload
from kinect_agent.commands.upload import upload_queue
from kinect_agent.config import AgentConfig, save_config
from kinect_agent.queue import SessionQueue
from kinect_agent.sources.simulator import simulate
from kinect_agent.upload import RetryPolicy, Uploader, drain
from tests.kinect_agent._backend import *  # noqa: F403  (the real server's fixtures: pytest registers those imported)
from tests.kinect_agent._backend import LOADED_S, LiveServer, free_port

FAST = RetryPolicy(max_attempts=3, base_delay_s=0.0)


class LoseFirstResponses(httpx.BaseTransport):
    """Forwards each request to the server, but throws away the first `n` responses after the server handled them."""

    def __init__(self, n: int) -> None:
        self.inner, self.n = httpx.HTTPTransport(), n
        self.statuses: list[int] = []

    def handle_request(self, request: httpx.Request) -> httpx.Response:
        response = self.inner.handle_request(request)
        response.read()
        self.statuses.append(response.status_code)
        if self.n:
            self.n -= 1
            raise httpx.ReadError("connection reset before the response arrived", request=request)
        return response


@pytest.fixture(scope="module")
def session_payload():
    """A simulated, filtered squat session (module-scoped: the filter takes a second or two)."""
    return make_payload(simulate("squat", 3, seed=11)[0])


@pytest.fixture
def paired(tmp_path, live_server, pairing_code):
    """(patient, device token) of a device paired through the API."""
    patient, code = pairing_code()
    pair = f"{live_server.url}/api/v1/devices/pair"
    r = httpx.post(pair, json={"code": code, "name": "upload test"}, timeout=LOADED_S)
    assert r.status_code == 201, r.text
    return patient, r.json()["token"]


def _stored(db_session, session_id: str) -> int:
    from backend.sessions.models import ExerciseSession

    return db_session.scalar(
        select(func.count()).select_from(ExerciseSession).where(ExerciseSession.client_session_id == session_id)
    )


def _client_id(session_id: str):
    import uuid

    return uuid.UUID(session_id)


def test_lost_response_is_retried_and_the_session_is_stored_once(
    tmp_path, live_server, paired, session_payload, db_session
) -> None:
    patient, token = paired
    queue = SessionQueue(tmp_path / "q")
    path = queue.enqueue(session_payload)
    lossy = LoseFirstResponses(1)
    with Uploader(live_server.url, token, transport=lossy, policy=FAST) as uploader:
        report = drain(queue, uploader)
    (result,) = report.results
    assert lossy.statuses == [201, 200], "the server stored the first request, then deduplicated the retry"
    assert result.outcome == "sent" and result.status_code == 200 and result.attempts == 2
    assert result.response["client_session_id"] == session_payload.session_id
    assert result.response["patient_id"] == patient.id
    assert not path.exists() and report.remaining == 0
    receipt = queue.receipt(session_payload.session_id)
    assert receipt is not None and receipt["server_session_id"] == result.response["id"]
    assert _stored(db_session, _client_id(session_payload.session_id)) == 1


def test_server_down_keeps_the_file_and_sends_it_later(tmp_path, app, paired, session_payload, db_session) -> None:
    _, token = paired
    port = free_port()
    queue = SessionQueue(tmp_path / "q")
    path = queue.enqueue(session_payload)
    later_file = queue.enqueue_bytes("7c9e6679-7425-40de-944b-e07fc1f90ae7", b"queued after the first")
    waits: list[float] = []
    policy = RetryPolicy(max_attempts=3, base_delay_s=0.5, max_delay_s=30.0)
    with Uploader(f"http://127.0.0.1:{port}", token, policy=policy, sleep=waits.append, rng=random.Random(1)) as up:
        down = drain(queue, up)
    assert [r.outcome for r in down.results] == ["kept"] and down.results[0].status_code is None
    assert down.results[0].attempts == 3 and len(waits) == 2
    assert 0 <= waits[0] <= 0.5 and 0 <= waits[1] <= 1.0, f"backoff with full jitter, got {waits}"
    assert path.exists() and later_file.exists() and down.remaining == 2, "the drain stops while the server is down"
    server = LiveServer(app, port).start()
    try:
        with Uploader(server.url, token, policy=FAST) as up:
            later = drain(queue, up)
    finally:
        server.stop()
    assert [r.status_code for r in later.results] == [201, 400] and later.remaining == 0
    assert _stored(db_session, _client_id(session_payload.session_id)) == 1


def test_invalid_file_is_moved_to_rejected_with_the_server_error(tmp_path, live_server, paired) -> None:
    _, token = paired
    queue = SessionQueue(tmp_path / "q")
    path = queue.enqueue_bytes("0b6f1f3e-3a4b-4a43-9d0a-2a4c7d1b5e60", b"this is not a session file")
    with Uploader(live_server.url, token, policy=FAST) as uploader:
        report = drain(queue, uploader)
    (result,) = report.results
    assert result.outcome == "rejected" and result.status_code == 400 and result.attempts == 1
    assert not path.exists() and (tmp_path / "q" / "rejected" / path.name).exists()
    error = queue.rejection(path.stem)
    assert error is not None
    assert error["status_code"] == 400 and error["response"]["error"] == "InvalidSessionFile"
    assert "bad_magic" in error["detail"]


def test_revoked_token_keeps_the_file(tmp_path, live_server, paired, session_payload) -> None:
    _, token = paired
    headers = {"Authorization": f"Bearer {token}"}
    me = httpx.get(f"{live_server.url}/api/v1/devices/me", headers=headers, timeout=LOADED_S).json()
    assert httpx.delete(f"{live_server.url}/api/v1/devices/{me['id']}", headers=headers).status_code == 204
    queue = SessionQueue(tmp_path / "q")
    path = queue.enqueue(session_payload)
    with Uploader(live_server.url, token, policy=FAST) as uploader:
        report = drain(queue, uploader)
    assert report.results[0].outcome == "kept" and report.results[0].status_code == 401
    assert path.exists()


def test_upload_command_drains_the_configured_queue(tmp_path, monkeypatch, live_server, paired, session_payload):
    _, token = paired
    monkeypatch.setenv("KINECT_AGENT_HOME", str(tmp_path / "agent"))
    queue_dir = tmp_path / "agent" / "queue"
    save_config(AgentConfig(server_url=live_server.url, device_token=token, queue_dir=str(queue_dir)))
    SessionQueue(queue_dir).enqueue(session_payload)
    from kinect_agent import cli

    assert cli.main(["upload", "--once"]) == 0
    assert SessionQueue(queue_dir).counts().sent == 1
    assert upload_queue().results == []
