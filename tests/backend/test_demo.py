"""The README's main job: `coach-server demo` migrates a fresh SQLite file, seeds the clinic and serves it."""

from __future__ import annotations

import datetime as dt
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import httpx
import pytest

from backend import demo


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def demo_args() -> list[str]:
    """Extra arguments of `coach-server demo` (overridden by tests that need other ones)."""
    return []


@pytest.fixture
def demo_server(tmp_path: Path, demo_args: list[str]):
    port = _free_port()
    proc = subprocess.Popen(
        [sys.executable, "-m", "backend.cli", "demo", "--port", str(port), "--db", str(tmp_path / "demo.db"),
         *demo_args],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=tmp_path,
    )  # fmt: skip
    assert proc.stdout is not None  # stdout=PIPE
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
        proc.wait(timeout=20)


@pytest.mark.own_database  # the demo runs on its own SQLite file
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
    out = proc.communicate(timeout=20)[0]
    assert f"{base}/docs" in out and "therapist@demo.clinic" in out
    assert "simulated home agents:" in out


def _demo_processes(marker: str) -> list[int]:
    """Returns the pids whose command line mentions `marker` (the test's own folder)."""
    pids = []
    for entry in Path("/proc").iterdir():
        try:
            if entry.name.isdigit() and marker in (entry / "cmdline").read_bytes().decode(errors="replace"):
                pids.append(int(entry.name))
        except OSError:
            continue
    return pids


@pytest.mark.own_database  # the demo runs on its own SQLite file
@pytest.mark.parametrize("demo_args", [["--history-weeks", "1", "--agent-interval", "1", "2"]])
def test_demo_agents_upload_backdated_and_live_sessions(demo_server, tmp_path: Path) -> None:
    """The simulated agents pair through the API and upload: history first (backdated), the queue drains."""
    base, proc = demo_server
    with httpx.Client(base_url=base, timeout=30) as client:
        login = client.post("/api/v1/auth/login", json={"email": "admin@demo.clinic", "password": demo.DEMO_PASSWORD})
        assert login.status_code == 200, login.text
        deadline = time.monotonic() + 240
        sessions: list[dict[str, Any]] = []
        while time.monotonic() < deadline and len(sessions) < 2:
            r = client.get("/api/v1/sessions", params={"limit": 100})
            assert r.status_code == 200, r.text
            sessions = r.json()["items"]
            assert proc.poll() is None, proc.stdout.read()
            time.sleep(2)
        assert len(sessions) >= 2, "the demo agents uploaded fewer than 2 sessions within 240 s"
        today = dt.datetime.now(dt.UTC).date().isoformat()
        assert any(s["started_at"][:10] < today for s in sessions), "backdated history comes first"
        devices = client.get(f"/api/v1/patients/{sessions[0]['patient_id']}/devices").json()["items"]
        assert any("home agent (simulated)" in d["name"] and d["last_seen_at"] for d in devices)
        patients = client.get("/api/v1/patients", params={"limit": 100}).json()["items"]
        first = next(p for p in patients if p["email"] == demo.PATIENTS[0][0])
        while time.monotonic() < deadline:  # the first patient's second agent serves live sets (kinect-agent serve)
            state = client.get("/api/v1/live/status", params={"patient_id": first["id"]}).json()["state"]
            if state == "online":
                break
            time.sleep(1)
        assert state == "online", "the demo's live home agent did not connect"
    receipts = list((tmp_path / "demo-agents").glob("*/queue/sent/*.json"))
    assert receipts, "the agents keep a receipt of every confirmed upload"
    assert not list((tmp_path / "demo-agents").glob("*/queue/rejected/*.khs"))
    proc.terminate()
    out = proc.communicate(timeout=30)[0]
    assert _demo_processes(str(tmp_path)) == [], "the agents stop with the demo"
    assert "history 1/" in out, "the backfill prints its progress"


def _start_demo(tmp_path: Path, *args: str) -> tuple[subprocess.Popen[str], str]:
    port = _free_port()
    proc = subprocess.Popen([sys.executable, "-m", "backend.cli", "demo", "--port", str(port), "--no-agents",
                             "--db", str(tmp_path / "demo.db"), *args],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=tmp_path)  # fmt: skip
    assert proc.stdout is not None  # stdout=PIPE
    base = f"http://127.0.0.1:{port}"
    for _ in range(120):
        try:
            if httpx.get(f"{base}/healthz", timeout=1).status_code == 200:
                return proc, base
        except httpx.TransportError:
            pass
        if proc.poll() is not None:
            pytest.fail(f"demo exited early:\n{proc.stdout.read()}")
        time.sleep(0.25)
    proc.kill()
    pytest.fail("demo server did not answer /healthz within 30 s")


def _stop(proc: subprocess.Popen[str]) -> str:
    proc.terminate()
    return proc.communicate(timeout=20)[0]


def _patients_named(base: str, name: str) -> int:
    with httpx.Client(base_url=base, timeout=30) as client:
        client.post("/api/v1/auth/login", json={"email": "admin@demo.clinic", "password": demo.DEMO_PASSWORD})
        users = client.get("/api/v1/users", params={"limit": 200}).json()["items"]
    return sum(u["full_name"] == name for u in users)


@pytest.mark.own_database  # the demo runs on its own SQLite file
def test_demo_keeps_its_database_between_runs_and_fresh_starts_over(tmp_path: Path) -> None:
    proc, base = _start_demo(tmp_path)
    try:
        with httpx.Client(base_url=base, timeout=30) as client:
            admin = {"email": "admin@demo.clinic", "password": demo.DEMO_PASSWORD}
            login = client.post("/api/v1/auth/login", json=admin)
            headers = {"X-CSRF-Token": login.json()["csrf_token"]}
            r = client.post("/api/v1/users", headers=headers, json={"email": "kept@demo.clinic", "role": "patient",
                            "password": "a-long-enough-password", "full_name": "Kept Patient"})  # fmt: skip
            assert r.status_code == 201, r.text
    finally:
        first = _stop(proc)
    assert "(new)" in first
    proc, base = _start_demo(tmp_path)
    try:
        assert _patients_named(base, "Kept Patient") == 1, "a second run keeps the database"
    finally:
        second = _stop(proc)
    assert "kept from the last run; --fresh starts over" in second
    proc, base = _start_demo(tmp_path, "--fresh")
    try:
        assert _patients_named(base, "Kept Patient") == 0, "--fresh starts over"
    finally:
        _stop(proc)


def test_logins_name_each_therapists_patients() -> None:
    text = demo.logins()
    assert "therapist@demo.clinic (Tara Therapist; patients: Rose Miller, Maria Rossi, Ines Garcia)" in text
    assert "rose@demo.clinic (Rose Miller; therapist: Tara Therapist)" in text
    assert "george@demo.clinic (George Brown; therapist: Paul Physio)" in text


def test_seed_demo_twice_changes_nothing(db_session) -> None:
    from sqlalchemy import func, select

    from backend.users.models import User

    demo.seed_demo(db_session)
    count = db_session.scalar(select(func.count()).select_from(User))
    demo.seed_demo(db_session)
    assert db_session.scalar(select(func.count()).select_from(User)) == count


def test_backfill_plan_is_patient_by_patient_oldest_first_and_repeatable(tmp_path: Path) -> None:
    from backend.demo_agents import SESSIONS_PER_WEEK, Agent, backfill_plan

    agents = [Agent(email=e, name=n, exercises=ex, index=i, home=tmp_path / str(i))
              for i, (e, n, ex) in enumerate(demo.PATIENTS)]  # fmt: skip
    today = dt.date(2026, 11, 23)
    plan = backfill_plan(agents, 3, today, seed=7)
    assert len(plan) == len(agents) * 2 * 3 * SESSIONS_PER_WEEK
    assert [a.index for _, a, _ in plan] == sorted(a.index for _, a, _ in plan)
    for agent in agents:
        times = [w for w, a, _ in plan if a is agent]
        assert times == sorted(times) and times[0].date() >= today - dt.timedelta(days=21)
        assert times[-1].date() < today
    assert [(w, a.email, x) for w, a, x in plan] == [(w, a.email, x) for w, a, x in backfill_plan(agents, 3, today, 7)]


def test_seed_demo_gives_every_demo_plan_reminder_times(db_session) -> None:
    """The demo patients' pages show a reminder: their plans have reminder times, and at 10:00 (the server's time
    zone, UTC here) the next one is 15:00."""
    from sqlalchemy import select

    from backend.config import Settings
    from backend.reminders.service import today
    from backend.users.models import User

    demo.seed_demo(db_session)
    settings = Settings(ENVIRONMENT="local", CHECK_MIGRATIONS=False, DATABASE_URL="sqlite://", TIME_ZONE="UTC")
    ten = dt.datetime.combine(dt.date.today(), dt.time(10, 0), tzinfo=dt.UTC)
    emails = [p[0] for p in demo.PATIENTS] + [demo.CAMERA_PATIENT[0]]
    for email in emails:
        patient = db_session.scalar(select(User).where(User.email == email))
        reminders = today(db_session=db_session, patient=patient, settings=settings, now=ten)
        assert [t.time for t in reminders.times] == ["09:00", "15:00", "20:00"], email
        assert reminders.next is not None and reminders.next.time == "15:00", email
