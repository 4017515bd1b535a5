"""The re-analysis queue at clinic scale: 10 000 stored 5-minute sessions, seeded in bulk (prints numbers; not a test).

    .venv/bin/python -m bench.records_scale --database-url postgresql+psycopg://postgres@127.0.0.1:5432/bench_x \
        [--sessions 10000] [--patients 100] [--window 120] [--workers 1 2]

Empties the database's public schema, migrates it, makes --files (2) distinct agent-made 5-minute session files
(simulated shoulder abduction through the pipeline, as uploads hold) in a local object store, and inserts
--sessions rows over --patients patients pointing to them with metrics documents of an older analysis version,
in bulk (one multi-row INSERT per 1 000 rows). Then times, on that database:
  * queueing all of them (`enqueue_reanalysis`, the code behind `coach-server reanalyze` and POST /reanalysis);
  * the admin page's API with 10 000 jobs (GET /reanalysis, GET /jobs?batch=, GET /reanalysis/{batch}), and
    GET /sessions/{id}/replay/state, through the ASGI app, median of 7;
  * claiming a job at the head of the 10 000-job queue (queue.claim, median of 50);
  * re-analysis throughput for --window seconds with 1 and with 2 `coach-server worker` processes on the full
    queue (sessions per second, peak RSS of one worker), and the hours the 10 000 would take at that rate.
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import resource
import signal
import statistics
import subprocess
import sys
import tempfile
import time
import uuid
from collections.abc import Callable
from functools import partial
from pathlib import Path

import sqlalchemy as sa
from sqlalchemy.orm import Session

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # `python bench/records_scale.py` puts bench/ first, not the repository
    sys.path.insert(0, str(ROOT))

from bench.reanalysis import session_files  # noqa: E402

CHUNK = 1000


def _fresh(url: str) -> sa.Engine:
    from backend.database import make_engine
    from backend.migrate import upgrade

    engine = make_engine(url)
    with engine.begin() as conn:
        if conn.dialect.name != "postgresql":
            raise SystemExit("use a PostgreSQL database (the bench empties its public schema)")
        conn.exec_driver_sql("DROP SCHEMA public CASCADE")
        conn.exec_driver_sql("CREATE SCHEMA public")
        upgrade(conn, "head")
    return engine


def seed(engine: sa.Engine, store_dir: str, files: list[bytes], sessions: int, patients: int) -> float:
    """Inserts the patients, sessions and metrics in bulk; returns the seconds it took."""
    from backend.exercises.models import Exercise
    from backend.exercises.service import sync_exercise_library
    from backend.sessions.models import ExerciseSession, SessionMetric
    from backend.storage.local import LocalStore
    from backend.users.models import User

    objs = [LocalStore(store_dir).put("session", f) for f in files]
    t0 = time.perf_counter()
    now = dt.datetime.now(dt.UTC)
    with Session(engine) as s, s.begin():
        sync_exercise_library(db_session=s)
        ex = s.scalar(sa.select(Exercise.id).where(Exercise.slug == "shoulder_abduction"))
        s.execute(sa.insert(User), [{"email": f"p{i}@bench.org", "role": "patient", "full_name": f"P {i}",
                                     "is_active": True, "created_at": now} for i in range(patients)])  # fmt: skip
        pids = list(s.scalars(sa.select(User.id).where(User.role == "patient").order_by(User.id)))
        for start in range(0, sessions, CHUNK):
            rows = []
            for i in range(start, min(start + CHUNK, sessions)):
                o = objs[i % len(objs)]
                rows.append({"client_session_id": uuid.uuid4(), "patient_id": pids[i % len(pids)], "exercise_id": ex,
                             "started_at": now - dt.timedelta(hours=i), "duration_s": 295.0, "n_frames": 8850,
                             "file_key": o.key, "file_size": o.size, "content_hash": o.sha256, "file_format": "khs",
                             "processing_version": "", "processing_params": {}, "status": "processed",
                             "created_at": now})  # fmt: skip
            ids = s.scalars(sa.insert(ExerciseSession).returning(ExerciseSession.id), rows).all()
            s.execute(sa.insert(SessionMetric), [{"session_id": sid, "document": {"repetitions": 80, "rom_deg": 1.0,
                      "quality": {"ok": True}}, "repetitions": 80, "rom_deg": 1.0, "created_at": now}
                      for sid in ids])  # fmt: skip
    return time.perf_counter() - t0


def _median_ms(fn: Callable[[], object], n: int) -> float:
    """Returns the median milliseconds of n calls of fn."""
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        fn()
        times.append((time.perf_counter() - t0) * 1000)
    return statistics.median(times)


def api_times(url: str, engine: sa.Engine, batch: str) -> dict[str, float]:
    """Returns the median milliseconds of the admin page's requests and of one replay-state request."""
    from fastapi.testclient import TestClient

    from backend.config import Settings
    from backend.main import create_app
    from backend.sessions.models import ExerciseSession
    from backend.users.models import User
    from backend.users.service import create_api_token, create_user

    with Session(engine) as s, s.begin():
        admin = s.scalar(sa.select(User).where(User.email == "admin@bench.org"))
        admin = admin or create_user(db_session=s, email="admin@bench.org", password=None, role="admin")
        _, token = create_api_token(db_session=s, user=admin, name="bench", scopes=["read"], days=1)
        sid = s.scalar(sa.select(sa.func.min(ExerciseSession.id)))
    headers = {"Authorization": f"Bearer {token}"}
    app = create_app(Settings(ENVIRONMENT="local", DATABASE_URL=url, CHECK_MIGRATIONS=False))
    out = {}
    with TestClient(app) as client:
        for name, path in (("GET /reanalysis", "/api/v1/reanalysis"),
                           ("GET /jobs?batch= (50 newest)", f"/api/v1/jobs?batch={batch}"),
                           ("GET /jobs?batch=&limit=500", f"/api/v1/jobs?batch={batch}&limit=500"),
                           ("GET /reanalysis/{batch}", f"/api/v1/reanalysis/{batch}"),
                           ("GET /sessions/{id}/replay/state", f"/api/v1/sessions/{sid}/replay/state")):  # fmt: skip
            r = client.get(path, headers=headers)
            assert r.status_code == 200, r.text
            out[name] = _median_ms(partial(client.get, path, headers=headers), 7)
    return out


def claim_ms(engine: sa.Engine) -> float:
    """Returns the median milliseconds of claiming the head of the queue (each claimed job is put back)."""
    from backend.jobs import queue
    from backend.jobs.models import Job

    times = []
    with Session(engine) as s:
        for _ in range(50):
            t0 = time.perf_counter()
            job = queue.claim(db_session=s, worker="bench", kinds=("reanalyze",))
            times.append((time.perf_counter() - t0) * 1000)
            assert job is not None
            s.execute(sa.update(Job).where(Job.id == job.id).values(status="queued", attempts=0, locked_by=None,
                                                                   locked_until=None))  # fmt: skip
            s.commit()
    return statistics.median(times)


def throughput(url: str, store_dir: str, engine: sa.Engine, workers: int, window_s: float) -> tuple[int, float, float]:
    """Runs `workers` worker processes for window_s on the queue; returns (jobs done, sessions/s, peak RSS MB)."""
    from backend.jobs.models import Job

    done_jobs = sa.select(sa.func.count()).select_from(Job).where(Job.status == "done")
    with engine.connect() as conn:
        before = conn.execute(done_jobs).scalar_one()
    env = os.environ | {"COACH_DATABASE_URL": url, "COACH_STORAGE_DIR": store_dir, "PYTHONPATH": str(ROOT)}
    cli = [sys.executable, "-m", "backend.cli", "worker"]
    t0 = time.perf_counter()
    procs = [subprocess.Popen(cli, env=env, stderr=subprocess.DEVNULL) for _ in range(workers)]
    time.sleep(window_s)
    for p in procs:
        p.send_signal(signal.SIGTERM)  # the job in hand is finished first
    for p in procs:
        p.wait()
    elapsed = time.perf_counter() - t0
    with engine.connect() as conn:
        done = conn.execute(done_jobs).scalar_one() - before
        failed = conn.scalar(sa.select(sa.func.count()).select_from(Job).where(Job.status == "failed"))
        twice = conn.scalar(sa.select(sa.func.count()).select_from(Job).where(Job.attempts > 1))
    assert failed == 0 and twice == 0, f"{failed} failed, {twice} taken twice"
    peak_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    return done, done / elapsed, peak_mb


def main() -> None:
    """Prints the seeding time, the queueing time, the admin API and claim latencies, and worker throughput."""
    ap = argparse.ArgumentParser()
    ap.add_argument("--database-url", required=True)
    ap.add_argument("--sessions", type=int, default=10_000)
    ap.add_argument("--patients", type=int, default=100)
    ap.add_argument("--files", type=int, default=2, help="distinct session files the rows point to")
    ap.add_argument("--window", type=float, default=120.0, help="seconds each worker count runs")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    args = ap.parse_args()
    os.environ["COACH_DATABASE_URL"] = args.database_url  # the app below uses the same database
    from backend.database import import_all_models
    from backend.records.reanalysis import enqueue_reanalysis

    import_all_models()
    files = session_files(args.files)
    print(f"session file: {len(files[0]) / 1e6:.2f} MB; {args.sessions} sessions of {args.patients} patients",
          flush=True)  # fmt: skip
    with tempfile.TemporaryDirectory() as store_dir:
        os.environ["COACH_STORAGE_DIR"] = store_dir  # the app below reads the same store
        engine = _fresh(args.database_url)
        print(f"seeded in bulk in {seed(engine, store_dir, files, args.sessions, args.patients):.1f} s", flush=True)
        t0 = time.perf_counter()
        with Session(engine) as s, s.begin():
            batch, added = enqueue_reanalysis(db_session=s)
        print(f"queued {added} re-analysis jobs in {time.perf_counter() - t0:.1f} s", flush=True)
        for name, ms in api_times(args.database_url, engine, batch).items():
            print(f"{name}: {ms:.1f} ms (median of 7, {added} jobs)", flush=True)
        print(f"claim at the head of the queue: {claim_ms(engine):.1f} ms (median of 50)", flush=True)
        for w in args.workers:
            done, rate, peak = throughput(args.database_url, store_dir, engine, w, args.window)
            hours = f"{10_000 / rate / 3600:.1f} h" if rate else "- (none finished in the window)"
            print(f"workers={w}: {done} sessions in {args.window:.0f} s = {rate:.2f} sessions/s; 10 000 would take "
                  f"{hours}; peak RSS of a worker {peak:.0f} MB", flush=True)  # fmt: skip
        engine.dispose()


if __name__ == "__main__":
    main()
