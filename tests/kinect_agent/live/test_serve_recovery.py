"""A home agent restarted after a crash is online at once: it filters the set the crash interrupted in the
background, and uploads that set exactly once. A real `kinect-agent serve` process against the real server (uvicorn
in this process), the interrupted set a 3-minute journal on its disk as a crash leaves it."""

# ruff: noqa: F811  (pytest fixtures are imported by name and then requested as arguments)

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
import uuid
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from backend.config import Settings
from kinect_agent.home import HomeAgent
from kinect_agent.live.journal import Journal
from kinect_agent.sources.simulator import simulate
from tests.kinect_agent._backend import (  # noqa: F401  (the real server's fixtures: pytest registers those imported)
    LOADED_S,
    LiveServer,
    app,
    auth_headers,
    db_connection,
    db_session,
    engine,
    held_open_settings,
    live_state,
    make_patient_with_therapist,
    make_user,
    pairing_code,
    test_database_url,
)

ROOT = Path(__file__).resolve().parents[3]
AGENT_START_S = 60.0  # an agent process imports numpy, SciPy and the filter before it connects: seconds when loaded
UPLOADED_S = 300.0  # filtering a 3-minute set (compiling the filter's kernels first on a fresh install), then sending


class CountingUploads:
    """The ASGI app, counting the session uploads (POST /api/v1/sessions) it is sent."""

    def __init__(self, inner) -> None:
        self.app, self.uploads = inner, 0

    async def __call__(self, scope, receive, send) -> None:
        if scope["type"] == "http" and scope["method"] == "POST" and scope["path"] == "/api/v1/sessions":
            self.uploads += 1
        await self.app(scope, receive, send)


@pytest.fixture
def settings() -> Settings:
    """The test server's settings with the agent's command stream held open."""
    return held_open_settings()


@pytest.fixture
def counted(app) -> CountingUploads:
    return CountingUploads(app)


@pytest.fixture
def live_server(counted) -> Iterator[LiveServer]:
    """The test app served over real HTTP (pairing_code's server too), its uploads counted."""
    server = LiveServer(counted).start()
    yield server
    server.stop()


def _interrupted_set(queue_dir: Path) -> str:
    """Writes the journal a crash 3 minutes into a set of squats leaves (frames flushed, never finished); returns
    its session id."""
    rec = simulate("squat", 40, seed=5)[0]
    session_id = str(uuid.uuid4())
    journal = Journal(queue_dir / "recording", session_id, rec.meta, "2026-11-28T08:00:00Z")
    for i in range(rec.n_frames):
        journal.append(rec.t[i], rec.positions[i], rec.state[i])
    journal.flush()
    return session_id


def test_a_restarted_agent_is_online_while_it_filters_the_interrupted_set(
    tmp_path, live_server, pairing_code, auth_headers, counted
):
    patient, code = pairing_code()
    headers = auth_headers(patient)
    home = tmp_path / "agent"
    agent = HomeAgent.pair(live_server.url, code, name="living room", home=home)
    queue_dir = Path(agent.config.queue_dir)
    session_id = _interrupted_set(queue_dir)
    journal = queue_dir / "recording" / f"{session_id}.json"
    assert live_state(live_server, headers) == "offline"
    env = os.environ | {"KINECT_AGENT_HOME": str(home), "PYTHONPATH": str(ROOT)}
    with open(tmp_path / "agent.log", "w+") as log:
        proc = subprocess.Popen([sys.executable, "-m", "kinect_agent.cli", "serve", "--source", "simulator"],
                                env=env, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT)  # fmt: skip
        try:
            started = time.monotonic()
            while live_state(live_server, headers) != "online":
                assert proc.poll() is None and time.monotonic() - started < AGENT_START_S, log.read()
                time.sleep(0.1)
            online_s = time.monotonic() - started
            recovering = journal.exists() and agent.where(session_id) in (None, "captured")
            assert recovering, (
                f"online after {online_s:.1f} s, but only once the set was queued ({agent.where(session_id)})"
            )
            while agent.where(session_id) != "sent":
                assert proc.poll() is None and time.monotonic() - started < UPLOADED_S, log.read()
                time.sleep(0.2)
            assert live_state(live_server, headers) == "online", "still online after the recovery"
        finally:
            proc.send_signal(signal.SIGTERM)
            try:
                proc.wait(timeout=60)
            except subprocess.TimeoutExpired:
                proc.kill()
        log.seek(0)
        said = log.read()
    assert proc.returncode == 0, said
    assert f"kept the interrupted set {session_id}" in said, said
    assert not journal.exists() and agent.queue.pending() == []
    assert counted.uploads == 1, f"the recovered set was sent {counted.uploads} times"
    r = httpx.get(f"{live_server.url}/api/v1/sessions", params={"patient_id": patient.id}, headers=headers,
                  timeout=LOADED_S)  # fmt: skip
    assert r.status_code == 200 and [s["client_session_id"] for s in r.json()["items"]] == [session_id], r.text
