"""End-to-end fixtures: the real server (uvicorn subprocess) on a migrated database seeded with the demo clinic
and sessions uploaded through the HTTP API, and one headless Chromium for the run.

COACH_TEST_DATABASE_URL picks the database as in tests/backend (default: a SQLite file in a temp dir); on
PostgreSQL the server uses its own schema coach_web_<pid>, dropped at the end.
"""

from __future__ import annotations

import datetime as dt
import os
import socket
import subprocess
import sys
import time
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import httpx
import pytest
from playwright.sync_api import Page, expect
from sqlalchemy.orm import Session

from backend.cli import KEEP_ALIVE_S
from backend.database import import_all_models
from backend.demo import DEMO_PASSWORD, seed_demo
from backend.migrate import upgrade
from tests.backend.conftest import build_engine, fast_password_hashing  # noqa: F401  (the seeded users' hashes)
from tests.backend.khs_files import make_khs

import_all_models()
# Every wait is for a condition; these are only how long a condition may take on a machine that runs other work
# too (two cores shared by several suites: a page that loads plotly.js took over 10 s). A passing test waits no
# longer for them.
expect.set_options(timeout=15_000)
PAGE_TIMEOUT_MS = 30_000
SERVER_START_S = 90  # uvicorn importing the app took over 30 s here with the machine busy

ROOT = Path(__file__).resolve().parents[2]
SHOTS = Path(os.environ.get("COACH_SHOTS_DIR", "/tmp/shots"))
CHROMIUM = os.environ.get("COACH_CHROMIUM", "/usr/bin/chromium")
THERAPIST = "therapist@demo.clinic"  # Tara: assigned to Rose (index 0), Maria, Ines
PATIENT = "rose@demo.clinic"  # plan: seated_knee_extension and sit_to_stand, 2 x 10, 3 per week


@dataclass
class LiveServer:
    """The running server and what the tests seeded into it."""

    url: str
    patient_id: int
    approved_text: str  # a suggestion approved through the API before the browser tests
    pending_ids: list[int] = field(default_factory=list)
    database_url: str = ""  # what the server process uses (PostgreSQL: with its schema)
    storage_dir: str = ""  # its object store (a second server on the same database must use the same one)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _server_url(url: str, schema: str | None) -> str:
    """Returns the database URL the server process uses (PostgreSQL: with search_path set to the test schema)."""
    if schema is None:
        return url
    return f"{url}{'&' if '?' in url else '?'}options=-csearch_path%3D{schema}"


def _login(client: httpx.Client, email: str) -> dict[str, Any]:
    r = client.post("/api/v1/auth/login", json={"email": email, "password": DEMO_PASSWORD})
    r.raise_for_status()
    return r.json()


def api_client(base: str, email: str) -> tuple[httpx.Client, dict[str, str]]:
    """Returns an httpx client of the server at base signed in as a demo user (login cookie) and its CSRF header;
    the caller closes the client (client.close(): a used httpx client cannot be entered with `with`)."""
    client = httpx.Client(base_url=base, timeout=60)
    return client, {"X-CSRF-Token": _login(client, email)["csrf_token"]}


NEW_PATIENT_PASSWORD = "new-patient-password-2026"


def plan_item(exercise: str, repetitions: int, sets: int = 2) -> dict[str, Any]:
    """One item of a plan as the API takes it (3 times a week)."""
    return {"exercise_slug": exercise, "sets": sets, "repetitions": repetitions, "frequency_per_week": 3}


@dataclass(frozen=True)
class NewPatient:
    """A patient created through the API by the demo admin (password NEW_PATIENT_PASSWORD)."""

    email: str
    id: int
    item_ids: list[int]  # the plan's items, in order ([] without a plan)
    pairing_code: str | None  # a fresh code for a home agent, when asked for


def create_patient(base: str, prefix: str, full_name: str, *, items: list[dict[str, Any]] | None = None,
                   plan: dict[str, Any] | None = None, settings: dict[str, Any] | None = None,
                   therapist: str | None = None, pairing_code: bool = False) -> NewPatient:  # fmt: skip
    """Creates a patient as the demo admin: optional patient settings (PATCH), a therapist assigned (by e-mail), a
    plan of `items` starting today (`plan` adds or overrides fields), and a pairing code."""
    email = f"{prefix}-{uuid.uuid4().hex[:8]}@example.org"
    admin, headers = api_client(base, "admin@demo.clinic")
    try:
        r = admin.post("/api/v1/users", json={"email": email, "role": "patient", "password": NEW_PATIENT_PASSWORD,
                                              "full_name": full_name}, headers=headers)  # fmt: skip
        assert r.status_code == 201, r.text
        pid = r.json()["id"]
        if settings:
            r = admin.patch(f"/api/v1/patients/{pid}", json=settings, headers=headers)
            assert r.status_code == 200, r.text
        if therapist:
            staff, _ = api_client(base, therapist)
            staff_id = staff.get("/api/v1/users/me").json()["id"]
            staff.close()
            assert admin.put(f"/api/v1/patients/{pid}/therapists/{staff_id}", headers=headers).status_code == 204
        item_ids: list[int] = []
        if items:
            today = time.strftime("%Y-%m-%d")
            body = {"title": "Plan", "start_date": today, "notes": "", "items": items} | (plan or {})
            r = admin.post(f"/api/v1/patients/{pid}/plans", json=body, headers=headers)
            assert r.status_code == 201, r.text
            item_ids = [item["id"] for item in r.json()["items"]]
        code = None
        if pairing_code:
            r = admin.post(f"/api/v1/patients/{pid}/pairing-codes", headers=headers)
            assert r.status_code == 201, r.text
            code = r.json()["code"]
    finally:
        admin.close()
    return NewPatient(email, pid, item_ids, code)


def upload_session(base: str, email: str, exercise: str, reps: int, *, seed: int,
                   created_at: str = "2026-11-20T10:00:00Z", data: bytes | None = None) -> dict[str, Any]:  # fmt: skip
    """Uploads a simulated set (tests.backend.khs_files.make_khs, or the file `data`) as the demo patient `email`;
    returns the stored session (201 asserted)."""
    client, headers = api_client(base, email)
    data = data or make_khs(exercise, reps, seed=seed, created_at=created_at)
    try:
        r = client.post(f"/api/v1/sessions?exercise={exercise}", content=data,
                        headers=headers | {"Content-Type": "application/octet-stream"})  # fmt: skip
    finally:
        client.close()
    assert r.status_code == 201, r.text
    return r.json()


def newest_session_id(base: str, email: str, patient_id: int | None = None) -> int:
    """Returns the id of the newest session the demo user `email` may see (of patient_id when given)."""
    client, _ = api_client(base, email)
    params = {"limit": 1} | ({"patient_id": patient_id} if patient_id is not None else {})
    try:
        r = client.get("/api/v1/sessions", params=params)
    finally:
        client.close()
    r.raise_for_status()
    return r.json()["items"][0]["id"]


def _iso(when: dt.datetime) -> str:
    return when.astimezone(dt.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


def _upload_history(base: str) -> tuple[int, str, list[int]]:
    """Uploads Rose's sessions as Rose (cookie + CSRF); approves one system suggestion as her therapist.

    Returns (patient id, the approved suggestion's text, ids of the suggestions still pending).
    """
    now = dt.datetime.now(dt.UTC).replace(microsecond=0)
    plan = [(21, "seated_knee_extension", 10), (17, "sit_to_stand", 10), (14, "seated_knee_extension", 10),
            (10, "sit_to_stand", 10), (7, "seated_knee_extension", 10), (3, "sit_to_stand", 10)]  # fmt: skip
    with httpx.Client(base_url=base, timeout=60) as rose:
        login = _login(rose, PATIENT)
        patient_id = login["user"]["id"]
        headers = {"X-CSRF-Token": login["csrf_token"], "Content-Type": "application/octet-stream"}
        uploads = [(now - dt.timedelta(days=d), slug, reps) for d, slug, reps in plan]
        # this week: a short sit-to-stand set a little earlier, a nearly complete knee set last
        uploads += [(now - dt.timedelta(minutes=90), "sit_to_stand", 6),
                    (now - dt.timedelta(minutes=30), "seated_knee_extension", 9)]  # fmt: skip
        for seed, (when, slug, reps) in enumerate(uploads):
            data = make_khs(slug, reps, seed=seed, created_at=_iso(when))
            r = rose.post(f"/api/v1/sessions?exercise={slug}", content=data, headers=headers)
            assert r.status_code == 201, r.text
    with httpx.Client(base_url=base, timeout=60) as tara:
        login = _login(tara, THERAPIST)
        r = tara.get(f"/api/v1/patients/{patient_id}/suggestions", params={"status": "pending", "limit": 200})
        pending = r.json()["items"]
        assert len(pending) >= 2, f"expected pending system suggestions, got {pending}"
        first = pending[-1]  # the oldest
        r = tara.post(f"/api/v1/suggestions/{first['id']}/approve", headers={"X-CSRF-Token": login["csrf_token"]})
        r.raise_for_status()
    return patient_id, first["text"], [s["id"] for s in pending[:-1]]


@pytest.fixture(scope="session")
def live_server(tmp_path_factory) -> Iterator[LiveServer]:
    """The app served by uvicorn in a subprocess on a free port, on a migrated and seeded database."""
    url = os.environ.get("COACH_TEST_DATABASE_URL") or f"sqlite:///{tmp_path_factory.mktemp('web') / 'web.db'}"
    engine, cleanup = build_engine(url, "coach_web")
    schema = f"coach_web_{os.getpid()}" if url.startswith("postgresql") else None
    with engine.begin() as conn:
        upgrade(conn, "head")
    from backend.exercises.service import sync_exercise_library

    with Session(engine) as session, session.begin():
        sync_exercise_library(db_session=session)
        seed_demo(session)
    engine.dispose()

    server_url = _server_url(url, schema)
    try:
        log_dir = tmp_path_factory.mktemp("log")
        with run_server(server_url, log_dir) as base:
            patient_id, approved, pending = _upload_history(base)
            yield LiveServer(url=base, patient_id=patient_id, approved_text=approved, pending_ids=pending,
                             database_url=server_url, storage_dir=str(log_dir / "objects"))  # fmt: skip
    finally:
        cleanup()  # after the server stopped


@contextmanager
def run_server(
    database_url: str, log_dir: Path, workers: int = 1, port: int | None = None, **env: str
) -> Iterator[str]:
    """Runs the app with uvicorn in a subprocess on `port` (default: a free port) of 127.0.0.1 (extra COACH_*
    settings in env), with `workers` worker processes; yields its base URL; stops it on exit."""
    port = port or free_port()
    # the embedded worker builds replays (backend/replay/jobs.py) as the demo's server does
    env = os.environ | {"COACH_DATABASE_URL": database_url, "COACH_ENVIRONMENT": "local", "PYTHONPATH": str(ROOT),
                        "COACH_STORAGE_DIR": str(log_dir / "objects"), "COACH_EMBEDDED_WORKER": "true",
                        **env}  # fmt: skip
    log = open(log_dir / f"server-{port}.log", "w+")  # noqa: SIM115 - closed below
    command = [sys.executable, "-m", "uvicorn", "backend.main:create_app", "--factory", "--host", "127.0.0.1",
               "--port", str(port), "--log-level", "warning", "--proxy-headers",
               "--forwarded-allow-ips", "127.0.0.1", "--timeout-graceful-shutdown", "2",
               "--timeout-keep-alive", str(KEEP_ALIVE_S),
               *(["--workers", str(workers)] if workers > 1 else [])]  # fmt: skip
    # the product's keep-alive (uvicorn's own 5 s let a test's client reuse a connection the server was closing)
    proc = subprocess.Popen(command, cwd=ROOT, env=env, stdout=log, stderr=subprocess.STDOUT)
    base = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + SERVER_START_S
        while True:
            try:
                if httpx.get(f"{base}/healthz", timeout=1).status_code == 200:
                    break
            except httpx.TransportError:
                pass
            if proc.poll() is not None or time.monotonic() > deadline:
                log.seek(0)
                pytest.fail(f"server did not start:\n{log.read()}")
            time.sleep(0.1)
        yield base
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
        log.close()


@pytest.fixture(scope="session")
def playwright_session():
    """Playwright for the run: one per process (a second sync_playwright() inside the first one fails), shared by
    the browser below and by tests that launch Chromium with their own flags (the fake camera)."""
    from playwright import sync_api

    if not Path(CHROMIUM).exists():
        if os.environ.get("CI"):
            pytest.fail(f"no Chromium at {CHROMIUM}; CI must install Debian's chromium (.ci/run does)")
        pytest.skip(f"no Chromium at {CHROMIUM} (apt-get install chromium, or set COACH_CHROMIUM)")
    with sync_api.sync_playwright() as pw:
        yield pw


@pytest.fixture(scope="session")
def browser(playwright_session):
    """One headless Chromium for the run (Debian's /usr/bin/chromium)."""
    b = playwright_session.chromium.launch(executable_path=CHROMIUM, headless=True, args=["--no-sandbox"])
    yield b
    b.close()


if TYPE_CHECKING:

    class CheckedPage(Page):
        """The page open_page yields: a Playwright page that also holds the script errors it had (page.js_errors),
        oldest first."""

        js_errors: list[str]


@contextmanager
def open_page(browser, base_url: str | None = None, width: int = 1280, height: int = 900, *,
              init_script: str | None = None, **context_options) -> Iterator[CheckedPage]:  # fmt: skip
    """Yields a page of a fresh browser context (no cookies) with a `width` x `height` px window at base_url;
    waits up to PAGE_TIMEOUT_MS, runs init_script before each document's scripts, collects script errors in
    page.js_errors; closes the context on exit. context_options go to Browser.new_context (ignore_https_errors=...).
    """
    context = browser.new_context(viewport={"width": width, "height": height}, base_url=base_url, **context_options)
    try:
        context.set_default_timeout(PAGE_TIMEOUT_MS)
        if init_script is not None:
            context.add_init_script(init_script)
        page = context.new_page()
        page.js_errors = []
        page.on("pageerror", lambda exc, errors=page.js_errors: errors.append(str(exc)))
        yield page
    finally:
        context.close()


@pytest.fixture
def page(browser, live_server):
    """A fresh browser context (no cookies) with a laptop-sized window."""
    with open_page(browser, live_server.url) as p:
        yield p


def sign_in(page, email: str, password: str = DEMO_PASSWORD) -> str:
    """Signs the page's context in through the API (login cookie, no page load); returns its CSRF token."""
    r = page.context.request.post("/api/v1/auth/login", data={"email": email, "password": password})
    assert r.ok, r.text()
    return r.json()["csrf_token"]


def login(page, email: str, password: str = DEMO_PASSWORD) -> None:
    """Signs in through the login form."""
    page.goto("/")
    page.fill("#email", email)
    page.fill("#password", password)
    page.click("#login-submit")


def shot(page, name: str) -> None:
    """Saves a full-page screenshot to /tmp/shots/<name>.png."""
    SHOTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(SHOTS / f"{name}.png"), full_page=True)
