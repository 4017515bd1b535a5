"""The README's main job: `coach-server demo` migrates a fresh SQLite file, seeds the clinic and serves it."""

from __future__ import annotations

import socket
import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest

from backend import demo


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def demo_server(tmp_path: Path):
    port = _free_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "backend.cli", "demo", "--port", str(port), "--db", str(tmp_path / "demo.db")],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=tmp_path,
    )  # fmt: skip
    base = f"http://127.0.0.1:{port}"
    try:
        for _ in range(120):
            try:
                if httpx.get(f"{base}/healthz", timeout=1).status_code == 200:
                    break
            except httpx.TransportError:
                pass
            if proc.poll() is not None:
                pytest.fail(f"demo exited early:\n{proc.stdout.read()}")
            time.sleep(0.25)
        else:
            pytest.fail("demo server did not answer /healthz within 30 s")
        yield base, proc
    finally:
        proc.terminate()
        proc.wait(timeout=10)


def test_demo_serves_the_seeded_clinic_and_prints_urls(demo_server) -> None:
    base, proc = demo_server
    with httpx.Client(base_url=base) as client:
        login = client.post(
            "/api/v1/auth/login", json={"email": "therapist@demo.clinic", "password": demo.DEMO_PASSWORD}
        )
        assert login.status_code == 200, login.text
        patients = client.get("/api/v1/patients")
        assert patients.status_code == 200, patients.text
        assert patients.json()["total"] == 3  # six demo patients shared by two therapists
        exercises = client.get("/api/v1/exercises", params={"limit": 100})
        assert exercises.json()["total"] >= 17
    proc.terminate()
    out = proc.communicate(timeout=10)[0]
    assert f"{base}/docs" in out and "therapist@demo.clinic" in out


def test_seed_demo_twice_changes_nothing(db_session) -> None:
    from sqlalchemy import func, select

    from backend.users.models import User

    demo.seed_demo(db_session)
    count = db_session.scalar(select(func.count()).select_from(User))
    demo.seed_demo(db_session)
    assert db_session.scalar(select(func.count()).select_from(User)) == count
