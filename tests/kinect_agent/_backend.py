"""The real coaching server for agent tests: the backend's test fixtures, and the app served by uvicorn.

The test modules that talk to the server import these fixtures (`from tests.kinect_agent._backend import *`: pytest
registers the fixtures a module imports); the agent's other tests never import the server, and run in the agent's own
environment too (tests/test_deployables.py).
"""

# ruff: noqa: F811  (pytest fixtures are imported by name and then requested as arguments)
from __future__ import annotations

import socket
import threading
import time
from collections.abc import Iterator

import pytest
import uvicorn

from backend.config import Settings
from tests.backend.conftest import (  # noqa: F401  (fixtures re-exported for the agent tests)
    app,
    auth_headers,
    db_connection,
    db_session,
    engine,
    make_patient_with_therapist,
    make_user,
    settings,
    test_database_url,
)

# the fixtures a test module gets with `import *`
__all__ = ["app", "auth_headers", "db_connection", "db_session", "engine", "live_server", "make_patient_with_therapist",
           "make_user", "pairing_code", "settings", "test_database_url"]  # fmt: skip


def free_port() -> int:
    """Returns a TCP port nobody listens on right now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class LiveServer:
    """uvicorn serving an ASGI app on 127.0.0.1:port in a thread; start() and stop() may be called repeatedly."""

    def __init__(self, app, port: int | None = None) -> None:
        self.app, self.port = app, port or free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self._server: uvicorn.Server | None = None
        self._thread: threading.Thread | None = None

    def start(self) -> LiveServer:
        config = uvicorn.Config(self.app, host="127.0.0.1", port=self.port, log_level="warning", lifespan="off")
        self._server = uvicorn.Server(config)
        self._thread = threading.Thread(target=self._server.run, daemon=True)
        self._thread.start()
        deadline = time.monotonic() + 20
        while not self._server.started:
            if time.monotonic() > deadline or not self._thread.is_alive():
                raise RuntimeError(f"uvicorn did not start on port {self.port}")
            time.sleep(0.02)
        return self

    def stop(self) -> None:
        if self._server is not None:
            self._server.should_exit = True
            assert self._thread is not None  # started with the server
            self._thread.join(timeout=20)
            self._server = None


LOADED_S = 60.0  # s: the tests' own requests wait this long (httpx's 5 s timed out in a CI pass at load 17-20)


def held_open_settings() -> Settings:
    """The test server's settings with the agent's command stream held open (EVENTS_STREAM_MAX_S), as deployed: for
    the tests where a real `kinect-agent serve` process stays connected."""
    return Settings(ENVIRONMENT="local", CHECK_MIGRATIONS=False, DATABASE_URL="sqlite://", EVENTS_STREAM_MAX_S=600.0,
                    LIVE_OFFLINE_GRACE_S=0.0, LIVE_WARM_UP=False)  # fmt: skip


def live_state(server: LiveServer, headers: dict[str, str]) -> str:
    """Returns the patient's home agent state as their page reads it (GET /api/v1/live/status): online, ..."""
    import httpx

    r = httpx.get(f"{server.url}/api/v1/live/status", headers=headers, timeout=LOADED_S)
    assert r.status_code == 200, r.text
    return r.json()["state"]


@pytest.fixture
def live_server(app) -> Iterator[LiveServer]:
    """The test app (bound to the rolled-back test session) served over real HTTP."""
    server = LiveServer(app).start()
    yield server
    server.stop()


@pytest.fixture
def pairing_code(live_server, make_patient_with_therapist, auth_headers):
    """Factory: pairing_code() -> (patient, code) created by the patient's therapist through the API."""
    import httpx

    def make():
        patient, therapist = make_patient_with_therapist()
        url = f"{live_server.url}/api/v1/patients/{patient.id}/pairing-codes"
        r = httpx.post(url, headers=auth_headers(therapist), timeout=LOADED_S)
        assert r.status_code == 201, r.text
        return patient, r.json()["code"]

    return make
