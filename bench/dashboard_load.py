"""Therapist dashboard API under concurrent load on PostgreSQL (prints numbers; not a test).

    .venv/bin/python bench/dashboard_load.py [--db URL] [--clients 50] [--duration 30] [--quick] [--json OUT]

Setup (not measured): drops and recreates the database of --db, migrates it with `coach-server migrate`, and
fills it with 100 patients x 100 sessions. Session rows carry real .khs files of simulated sets and the metrics
documents the ingest writes for them (analysis of a pool of simulated recordings, indicators computed per
session against that patient's earlier sessions and plan target), plus running plans, pending suggestions and
5 therapists with 20 assigned patients each. Then it starts the real server (uvicorn, backend.main:create_app,
--workers N) on a free port, logs 50 clients in as therapists (POST /api/v1/auth/login, cookie sessions as the
browser dashboard does) and lets each run a dashboard request mix for --duration seconds:

    GET /api/v1/dashboard                        the overview of all the therapist's patients
    GET /api/v1/patients                         the patient list
    GET /api/v1/patients/{id}/summary            one patient's card
    GET /api/v1/patients/{id}/progress           one patient's time series (100 points)
    GET /api/v1/sessions?patient_id=..&limit=20  one patient's session list
    GET /api/v1/sessions/{id}                    one session with its metrics document

Clients are closed-loop: each waits for its answer, then thinks --think seconds (exponentially distributed,
mean --think; 0 = back-to-back) before its next request. Reports requests, errors (any non-2xx or transport
error), throughput and p50/p95/p99 latency per endpoint and overall; PASS when p95 <= --target-ms and no errors.
"""

from __future__ import annotations

import argparse
import asyncio
import datetime as dt
import hashlib
import json
import os
import random
import socket
import subprocess
import sys
import time
import uuid
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from kinect_agent.analysis.document import AnalysisReport
    from kinect_agent.formats.session_file import SessionPayload

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import httpx  # noqa: E402
from sqlalchemy import create_engine, insert, select, text  # noqa: E402
from sqlalchemy.engine import make_url  # noqa: E402
from sqlalchemy.orm import Session  # noqa: E402

DEFAULT_DB = "postgresql+psycopg://postgres@127.0.0.1:5432/coach_bench"
PASSWORD = "bench-password-2026"
N_THERAPISTS = 5
EXERCISE_PAIRS = (
    ("squat", "sit_to_stand"),
    ("shoulder_abduction", "elbow_flexion"),
    ("seated_knee_extension", "standing_leg_raise"),
    ("shoulder_flexion", "side_step"),
)
POOL_PER_EXERCISE = 6  # distinct simulated recordings per exercise (seed and repetitions vary)
KEEP_ALIVE_S = 75  # server keep-alive, s (a browser keeps idle connections about a minute)
HISTORY = 12  # earlier documents passed to the indicators, like session_history's 4-week window
# (endpoint name, weight): what a therapist clicks through
MIX = (
    ("dashboard", 15),
    ("patients", 5),
    ("summary", 15),
    ("progress", 15),
    ("sessions", 25),
    ("session", 25),
)


# ------------------------------------------------------------------------------------------------ setup


def recreate_database(url: str) -> None:
    """Drops and creates the database of url (connecting to the server's 'postgres' database)."""
    target = make_url(url)
    if target.get_backend_name() != "postgresql":
        raise SystemExit("--db must be a PostgreSQL URL")
    admin = create_engine(target.set(database="postgres"), isolation_level="AUTOCOMMIT")
    name = target.database
    with admin.connect() as conn:
        conn.execute(text(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)'))
        conn.execute(text(f'CREATE DATABASE "{name}"'))
    admin.dispose()


def migrate(url: str) -> None:
    """Runs `coach-server migrate` (Alembic to head, exercise library synced) as an operator would."""
    env = {**os.environ, "COACH_DATABASE_URL": url}
    subprocess.run([str(Path(sys.executable).parent / "coach-server"), "migrate"], env=env, check=True, cwd=ROOT)


def _pool(exercises: list[str], per_exercise: int) -> dict[str, list[tuple[bytes, SessionPayload, AnalysisReport]]]:
    """Returns per exercise a list of (.khs bytes, decoded payload, analysis document) of simulated sets."""
    from kinect_agent.analysis.exercise import EXERCISES
    from kinect_agent.analysis.report import analyze_recording
    from kinect_agent.formats import session_file as sf
    from kinect_agent.sources.simulator import simulate

    pool: dict[str, list[tuple[bytes, SessionPayload, AnalysisReport]]] = {}
    for slug in exercises:
        pool[slug] = []
        for k in range(per_exercise):
            measured, truth, _ = simulate(slug, 6 + k % 5, seed=100 + k, view_deg=(0, 30)[k % 2])
            payload = sf.SessionPayload(
                session_id=str(uuid.uuid4()),
                raw=measured,
                filtered=truth,
                params={"filter": "ukf"},
                created_at="2026-11-20T10:00:00Z",
            )
            data = sf.encode(payload)
            doc = analyze_recording(payload.raw, EXERCISES[slug], filtered=payload.filtered)
            pool[slug].append((data, payload, doc))
    return pool


def seed(url: str, n_patients: int, n_sessions: int, per_exercise: int) -> dict[str, Any]:
    """Fills the migrated database; returns {"therapists": [email, ...], "sessions": n, "file_mib": x}."""
    from backend import __version__
    from backend.database import import_all_models, utcnow
    from backend.exercises.models import Exercise
    from backend.patients.models import TherapistPatient
    from backend.plans.models import Plan, PlanItem
    from backend.security import hash_password
    from backend.sessions.metrics import scalar_columns
    from backend.sessions.models import ExerciseSession, SessionMetric
    from backend.suggestions.models import Suggestion
    from backend.users.models import User
    from kinect_agent.analysis.document import read_document
    from kinect_agent.analysis.exercise import EXERCISES
    from kinect_agent.analysis.indicators import indicators

    import_all_models()
    slugs = sorted({s for pair in EXERCISE_PAIRS for s in pair})
    pool = _pool(slugs, per_exercise)
    rng = random.Random(7)
    now = utcnow().replace(microsecond=0)
    engine = create_engine(url)
    file_bytes = 0
    with Session(engine) as s, s.begin():
        exercise_ids = dict(s.execute(select(Exercise.slug, Exercise.id).where(Exercise.slug.in_(slugs))).all())
        password_hash = hash_password(PASSWORD)
        therapists = [
            {"email": f"therapist{t}@bench.clinic", "full_name": f"Therapist {t}", "role": "therapist",
             "password_hash": password_hash, "created_at": now}
            for t in range(N_THERAPISTS)
        ]  # fmt: skip
        therapist_ids = list(s.scalars(insert(User).returning(User.id), therapists))
        patients = [
            {"email": f"patient{i:03d}@bench.clinic", "full_name": f"Patient {i:03d}", "role": "patient",
             "password_hash": None, "created_at": now - dt.timedelta(days=120)}
            for i in range(n_patients)
        ]  # fmt: skip
        patient_ids = list(s.scalars(insert(User).returning(User.id), patients))
        s.execute(
            insert(TherapistPatient),
            [{"therapist_id": therapist_ids[i % N_THERAPISTS], "patient_id": pid, "created_at": now}
             for i, pid in enumerate(patient_ids)],
        )  # fmt: skip
    for i, pid in enumerate(patient_ids):
        pair = EXERCISE_PAIRS[i % len(EXERCISE_PAIRS)]
        target = {slug: 8 + (i + j) % 5 for j, slug in enumerate(pair)}
        with Session(engine) as s, s.begin():
            plan_id = s.scalar(
                insert(Plan).returning(Plan.id),
                {"patient_id": pid, "therapist_id": therapist_ids[i % N_THERAPISTS], "title": "Home programme",
                 "notes": "", "start_date": (now - dt.timedelta(days=n_sessions)).date(),
                 "end_date": (now + dt.timedelta(days=28)).date(), "created_at": now, "updated_at": now},
            )  # fmt: skip
            s.execute(
                insert(PlanItem),
                [{"plan_id": plan_id, "exercise_id": exercise_ids[slug], "sets": 2, "repetitions": target[slug],
                  "frequency_per_week": 3, "position": j} for j, slug in enumerate(pair)],
            )  # fmt: skip
            history: dict[str, list[AnalysisReport]] = {slug: [] for slug in pair}
            rows, docs = [], []
            for k in range(n_sessions):  # oldest first, about one session a day, the newest a few hours ago
                slug = pair[k % 2]
                data, payload, base = pool[slug][rng.randrange(len(pool[slug]))]
                started = now - dt.timedelta(days=(n_sessions - 1 - k) * 0.9, hours=3 + rng.random() * 6)
                found = indicators(
                    base, exercise=EXERCISES[slug], target_reps=target[slug], history=history[slug][-HISTORY:]
                )
                doc = base.model_dump(mode="json") | {"indicators": found.model_dump(mode="json"),
                                                      "analysis_version": "bench"}  # fmt: skip
                history[slug].append(base)
                docs.append(doc)
                file_bytes += len(data)
                rows.append(
                    {"client_session_id": uuid.uuid4(), "patient_id": pid, "device_id": None,
                     "exercise_id": exercise_ids[slug], "started_at": started, "duration_s": payload.raw.duration,
                     "n_frames": payload.raw.n_frames, "file_format": "khs", "file_bytes": data,
                     "file_size": len(data), "content_hash": hashlib.sha256(data).hexdigest(),
                     "processing_version": __version__, "processing_params": {"filter": "ukf"},
                     "status": "processed", "error": None, "created_at": started + dt.timedelta(minutes=2)}
                )  # fmt: skip
            session_ids = list(s.scalars(insert(ExerciseSession).returning(ExerciseSession.id), rows))
            s.execute(
                insert(SessionMetric),
                [{"session_id": sid, "document": doc, "created_at": row["created_at"],
                  **scalar_columns(read_document(doc))} for sid, doc, row in zip(session_ids, docs, rows, strict=True)],
            )  # fmt: skip
            if i % 4:
                s.execute(
                insert(Suggestion),
                [{"patient_id": pid, "session_id": session_ids[-1 - j], "source": "system", "rule": "rom_drop",
                  "metric": "rom_deg", "comparison": "<", "threshold": 0.8, "text": "Range of motion dropped.",
                  "status": ("pending", "approved", "dismissed")[j % 3], "created_at": now}
                 for j in range(i % 4)],
            )  # fmt: skip
    engine.dispose()
    autocommit = create_engine(url, isolation_level="AUTOCOMMIT")
    with autocommit.connect() as conn:
        conn.execute(text("VACUUM ANALYZE"))  # what autovacuum does soon after a bulk load
    autocommit.dispose()
    return {
        "therapists": [t["email"] for t in therapists],
        "sessions": n_patients * n_sessions,
        "file_mib": file_bytes / 2**20,
    }


# ------------------------------------------------------------------------------------------------ server


def free_port() -> int:
    """Returns a TCP port that is free on 127.0.0.1 now."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


START_S = 240  # the server may take minutes to start on the shared 2 cores at load 15


def start_server(url: str, port: int, workers: int) -> subprocess.Popen[bytes]:
    """Starts uvicorn with backend.main:create_app on port; returns once /healthz answers 200."""
    env = {**os.environ, "COACH_DATABASE_URL": url, "COACH_ENVIRONMENT": "local"}
    command = [sys.executable, "-m", "uvicorn", "backend.main:create_app", "--factory", "--host", "127.0.0.1",
               "--port", str(port), "--workers", str(workers), "--no-access-log", "--log-level", "warning",
               # keep idle connections longer than a client thinks (uvicorn's default 5 s races with reuse)
               "--timeout-keep-alive", str(KEEP_ALIVE_S)]  # fmt: skip
    server = subprocess.Popen(command, env=env, cwd=ROOT)
    deadline = time.monotonic() + START_S
    while time.monotonic() < deadline:
        if server.poll() is not None:
            raise SystemExit(f"server exited with status {server.returncode}")
        try:
            if httpx.get(f"http://127.0.0.1:{port}/healthz", timeout=1).status_code == 200:
                return server
        except httpx.HTTPError:
            pass
        time.sleep(0.3)
    server.terminate()
    raise SystemExit(f"server did not answer /healthz within {START_S} s")


def stop_server(server: subprocess.Popen[bytes]) -> None:
    """Stops the server (SIGTERM, SIGKILL after 15 s)."""
    server.terminate()
    try:
        server.wait(timeout=15)
    except subprocess.TimeoutExpired:
        server.kill()
        server.wait()


# ------------------------------------------------------------------------------------------------ load


class Client:
    """One therapist's browser: a cookie session, its patients and the sessions it has seen."""

    def __init__(self, base: str, email: str, seed: int) -> None:
        self.http = httpx.AsyncClient(base_url=base, timeout=30.0)
        self.email = email
        self.rng = random.Random(seed)
        self.patients: list[int] = []
        self.sessions: dict[int, list[int]] = {}

    async def login(self) -> None:
        response = await self.http.post("/api/v1/auth/login", json={"email": self.email, "password": PASSWORD})
        response.raise_for_status()
        page = (await self.http.get("/api/v1/dashboard", params={"limit": 200})).json()
        self.patients = [row["patient_id"] for row in page["items"]]
        if not self.patients:
            raise SystemExit(f"{self.email} sees no patients")

    def request(self, name: str) -> tuple[str, dict[str, int]]:
        """Returns (path, query) of one request of kind name."""
        pid = self.rng.choice(self.patients)
        if name == "dashboard":
            return "/api/v1/dashboard", {"limit": 50}
        if name == "patients":
            return "/api/v1/patients", {"limit": 50}
        if name == "summary":
            return f"/api/v1/patients/{pid}/summary", {}
        if name == "progress":
            return f"/api/v1/patients/{pid}/progress", {}
        if name == "session" and self.sessions:
            ids = self.sessions[self.rng.choice(list(self.sessions))]
            return f"/api/v1/sessions/{self.rng.choice(ids)}", {}
        return "/api/v1/sessions", {"patient_id": pid, "limit": 20}

    async def run(
        self, stop_at: float, think: float, samples: list[tuple[str, float]], errors: list[str], record: bool
    ) -> None:
        names = [n for n, _ in MIX]
        weights = [w for _, w in MIX]
        while time.monotonic() < stop_at:
            name = self.rng.choices(names, weights)[0]
            path, query = self.request(name)
            if name == "session" and not path.startswith("/api/v1/sessions/"):
                name = "sessions"
            start = time.perf_counter()
            response: httpx.Response | None = None
            try:
                response = await self.http.get(path, params=query)
                status = str(response.status_code)
            except httpx.HTTPError as exc:
                status = f"{type(exc).__name__}"
            elapsed = time.perf_counter() - start
            if record:
                samples.append((name, elapsed))
            if response is None or not 200 <= response.status_code < 300:
                if record:
                    errors.append(f"{name} {path}: {status}")
            elif name == "sessions":
                items = response.json()["items"]
                if items:
                    self.sessions[items[0]["patient_id"]] = [item["id"] for item in items]
            if think > 0:  # never past the end, so the measured seconds are the window the requests started in
                await asyncio.sleep(min(self.rng.expovariate(1 / think), max(0.0, stop_at - time.monotonic())))


async def run_load(
    base: str, therapists: list[str], clients: int, duration: float, warmup: float, think: float
) -> tuple[list[tuple[str, float]], list[str], float]:
    """Logs clients in, warms up, then measures; returns (samples [(endpoint, seconds)], errors, seconds)."""
    pool = [Client(base, therapists[i % len(therapists)], seed=i) for i in range(clients)]
    for client in pool:  # one after the other: argon2 logins are setup, not the dashboard
        await client.login()
    samples: list[tuple[str, float]] = []
    errors: list[str] = []
    try:
        stop = time.monotonic() + warmup
        await asyncio.gather(*(c.run(stop, think, [], [], record=False) for c in pool))
        start = time.monotonic()
        await asyncio.gather(*(c.run(start + duration, think, samples, errors, record=True) for c in pool))
        elapsed = time.monotonic() - start
    finally:
        await asyncio.gather(*(c.http.aclose() for c in pool))
    return samples, errors, elapsed


def percentile(values: list[float], q: float) -> float:
    """Returns the q-th percentile (0..100) by linear interpolation of sorted values."""
    ordered = sorted(values)
    if not ordered:
        return float("nan")
    pos = (len(ordered) - 1) * q / 100
    low = int(pos)
    high = min(low + 1, len(ordered) - 1)
    return ordered[low] + (ordered[high] - ordered[low]) * (pos - low)


def stats(samples: list[tuple[str, float]], errors: list[str], elapsed: float) -> dict[str, Any]:
    """Returns request counts, throughput and latency percentiles (ms) per endpoint and overall."""

    def summary(times: list[float]) -> dict[str, Any]:
        ms = [1000 * t for t in times]
        return {
            "requests": len(ms),
            "rps": len(ms) / elapsed,
            "p50_ms": percentile(ms, 50),
            "p95_ms": percentile(ms, 95),
            "p99_ms": percentile(ms, 99),
            "max_ms": max(ms) if ms else float("nan"),
        }

    per = {name: summary([t for n, t in samples if n == name]) for name, _ in MIX}
    return {"overall": summary([t for _, t in samples]), "endpoints": per, "errors": len(errors),
            "error_examples": errors[:10], "seconds": elapsed}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--db", default=DEFAULT_DB, help=f"PostgreSQL URL of a database to RECREATE (default {DEFAULT_DB})"
    )
    parser.add_argument("--clients", type=int, default=50)
    parser.add_argument("--duration", type=float, default=30.0, help="measured seconds")
    parser.add_argument("--warmup", type=float, default=5.0, help="unmeasured seconds of load first")
    parser.add_argument("--think", type=float, default=1.0, help="mean think time of a client between requests, s")
    parser.add_argument("--workers", type=int, default=2, help="uvicorn worker processes")
    parser.add_argument("--patients", type=int, default=100)
    parser.add_argument("--sessions", type=int, default=100, help="sessions per patient")
    parser.add_argument("--target-ms", type=float, default=150.0, help="p95 target")
    parser.add_argument("--reuse", action="store_true", help="keep the database of an earlier run (no re-seeding)")
    parser.add_argument("--quick", action="store_true", help="20 patients x 20 sessions, 10 clients, 5 s")
    parser.add_argument("--json", type=Path, help="also write the results to this JSON file")
    args = parser.parse_args(argv)
    if args.quick:
        args.patients, args.sessions, args.clients, args.duration, args.warmup = 20, 20, 10, 5.0, 1.0
    per_exercise = 2 if args.quick else POOL_PER_EXERCISE

    setup: dict[str, Any] = {}
    if args.reuse:
        setup = {"therapists": [f"therapist{t}@bench.clinic" for t in range(N_THERAPISTS)], "reused": True}
    else:
        t0 = time.perf_counter()
        recreate_database(args.db)
        migrate(args.db)
        setup = seed(args.db, args.patients, args.sessions, per_exercise)
        setup["seconds"] = time.perf_counter() - t0
        print(f"seeded {args.patients} patients x {args.sessions} sessions ({setup['file_mib']:.0f} MiB of .khs "
              f"files), {N_THERAPISTS} therapists, in {setup['seconds']:.0f} s", flush=True)  # fmt: skip
    port = free_port()
    server = start_server(args.db, port, args.workers)
    try:
        load_before = os.getloadavg()
        samples, errors, elapsed = asyncio.run(
            run_load(f"http://127.0.0.1:{port}", setup["therapists"], args.clients, args.duration, args.warmup,
                     args.think)
        )  # fmt: skip
        load_after = os.getloadavg()
    finally:
        stop_server(server)
    result = stats(samples, errors, elapsed)
    overall = result["overall"]
    passed = result["errors"] == 0 and overall["p95_ms"] <= args.target_ms
    result.update(
        {
            "date": dt.date.today().isoformat(),
            "config": {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()},
            "cpus": os.cpu_count(),
            "loadavg_before": load_before,
            "loadavg_after": load_after,
            "pass": passed,
        }
    )
    print(f"\n{args.clients} clients, think {args.think:g} s, {args.workers} uvicorn workers, {elapsed:.1f} s "
          f"measured; load average before {load_before[0]:.2f}, after {load_after[0]:.2f} "
          f"({os.cpu_count()} CPUs)")  # fmt: skip
    print(f"{'endpoint':<10} {'requests':>8} {'req/s':>7} {'p50 ms':>8} {'p95 ms':>8} {'p99 ms':>8} {'max ms':>8}")
    for name, row in [*result["endpoints"].items(), ("overall", overall)]:
        print(f"{name:<10} {row['requests']:>8} {row['rps']:>7.1f} {row['p50_ms']:>8.1f} {row['p95_ms']:>8.1f} "
              f"{row['p99_ms']:>8.1f} {row['max_ms']:>8.1f}")  # fmt: skip
    print(f"errors: {result['errors']} {result['error_examples'][:3] if errors else ''}")
    print(f"p95 {overall['p95_ms']:.1f} ms vs target {args.target_ms:g} ms, errors {result['errors']}: "
          f"{'PASS' if passed else 'FAIL'}")  # fmt: skip
    if args.json:
        args.json.write_text(json.dumps(result, indent=2))
    return 0 if passed else 1


if __name__ == "__main__":
    raise SystemExit(main())
