"""Re-analysis throughput: N stored 5-minute sessions re-analysed by 1 and by 2 `coach-server worker` processes.

    .venv/bin/python -m bench.reanalysis --database-url postgresql+psycopg://postgres@127.0.0.1:5432/bench_x \
        [--sessions 200] [--workers 1 2] [--pipeline]

Makes --files (4) distinct agent-made 5-minute session files (simulated shoulder abduction through the pipeline, raw +
filtered + angle SDs, as uploads hold), stores them in a local object store, and inserts N session rows pointing to
them (round robin) with metrics documents of an older analysis version. Then, per worker count: queue every
session (coach-server reanalyze) and time until the queue is empty; prints sessions per second and the peak RSS of
one worker (ru_maxrss of the worker processes). Extrapolate to 10 000 sessions as N / rate.

--pipeline: the files are filtered by the agent with other settings than today's (sigma_tracked_m 0.03 m), and the
batch is `coach-server reanalyze --pipeline`: each job filters the raw recording again, writes a new file, and
recomputes the metrics (the cost of a re-analysis after a pipeline change).
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import resource
import subprocess
import sys
import tempfile
import time
import uuid
from pathlib import Path

import sqlalchemy as sa
from sqlalchemy.orm import Session

ROOT = Path(__file__).resolve().parents[1]


def session_files(n: int, *, stale: bool = False) -> list[bytes]:
    """Returns n distinct agent-made 5-minute session files; stale: filtered with other settings than today's."""
    from kinect_agent.capture import make_payload
    from kinect_agent.formats import session_file as sf
    from kinect_agent.processing.config import PipelineConfig
    from kinect_agent.sources.simulator import simulate

    config = PipelineConfig(sigma_tracked_m=0.03) if stale else None
    out = []
    for seed in range(n):
        measured, _, _ = simulate("shoulder_abduction", 80, seed=seed)  # ~ 290-300 s at 30 Hz
        out.append(sf.encode(make_payload(measured, created_at="2026-11-20T10:00:00Z", config=config)))
    return out


def _setup(url: str, store_dir: str, n: int, files: list[bytes]) -> None:
    from backend.database import make_engine
    from backend.exercises.models import Exercise
    from backend.exercises.service import sync_exercise_library
    from backend.jobs.models import Job
    from backend.migrate import upgrade
    from backend.sessions.models import ExerciseSession, SessionMetric
    from backend.storage.local import LocalStore
    from backend.users.models import User

    store = LocalStore(store_dir)
    objs = [store.put("session", f) for f in files]
    engine = make_engine(url)
    with engine.begin() as conn:  # a clean database each run (a downgrade would first move the files back)
        if conn.dialect.name == "postgresql":
            conn.exec_driver_sql("DROP SCHEMA public CASCADE")
            conn.exec_driver_sql("CREATE SCHEMA public")
        else:
            raise SystemExit("use a PostgreSQL database (the bench empties its public schema)")
        upgrade(conn, "head")
    now = dt.datetime.now(dt.UTC)
    with Session(engine) as s, s.begin():
        sync_exercise_library(db_session=s)
        patient = User(email="bench@example.org", role="patient", full_name="Bench")
        s.add(patient)
        s.flush()
        ex = s.scalar(sa.select(Exercise.id).where(Exercise.slug == "shoulder_abduction"))
        for i in range(n):
            o = objs[i % len(objs)]
            row = ExerciseSession(client_session_id=uuid.uuid4(), patient_id=patient.id, exercise_id=ex,
                                  started_at=now - dt.timedelta(hours=i), duration_s=295.0, n_frames=8850,
                                  file_key=o.key, file_size=o.size, content_hash=o.sha256,
                                  file_format="khs")  # fmt: skip
            s.add(row)
            s.flush()
            s.add(SessionMetric(session_id=row.id, document={"repetitions": 80, "rom_deg": 1.0,
                                                             "quality": {"ok": True}}, repetitions=80))  # fmt: skip
        s.execute(sa.delete(Job))
    engine.dispose()


def _cpu_s() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def _run(url: str, store_dir: str, workers: int, n: int, pipeline: bool = False) -> tuple[float, float, float]:
    """Returns sessions per second (wall), CPU seconds of the workers per session, and the peak RSS in MB."""
    env = os.environ | {"COACH_DATABASE_URL": url, "COACH_STORAGE_DIR": store_dir, "PYTHONPATH": str(ROOT)}
    cli = [sys.executable, "-m", "backend.cli"]
    subprocess.run([*cli, "reanalyze", *(["--pipeline"] if pipeline else [])], env=env, check=True,
                   capture_output=True)  # fmt: skip
    cpu0, t0 = _cpu_s(), time.perf_counter()
    procs = [subprocess.Popen([*cli, "worker", "--once"], env=env, stderr=subprocess.DEVNULL) for _ in range(workers)]
    for p in procs:
        p.wait()
    elapsed = time.perf_counter() - t0
    cpu_per_session = (_cpu_s() - cpu0) / n  # includes each worker's start (imports), about 2-3 s of CPU
    peak_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    return n / elapsed, cpu_per_session, peak_mb


def main() -> None:
    """Prints sessions per second and peak worker RSS for each worker count."""
    ap = argparse.ArgumentParser()
    ap.add_argument("--database-url", required=True)
    ap.add_argument("--sessions", type=int, default=200)
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--files", type=int, default=4, help="distinct session files the rows point to")
    ap.add_argument("--pipeline", action="store_true", help="stale files, `reanalyze --pipeline` (module doc)")
    args = ap.parse_args()
    files = session_files(args.files, stale=args.pipeline)
    mode = "pipeline + metrics" if args.pipeline else "metrics only"
    print(f"session file: {len(files[0]) / 1e6:.2f} MB, {args.sessions} sessions, {mode}", flush=True)
    with tempfile.TemporaryDirectory() as store_dir:
        for w in args.workers:
            _setup(args.database_url, store_dir, args.sessions, files)
            rate, cpu, peak = _run(args.database_url, store_dir, w, args.sessions, args.pipeline)
            print(f"workers={w}: {rate:.2f} sessions/s, 10 000 sessions in {10000 / rate / 3600:.1f} h, "
                  f"{cpu:.2f} s CPU per session, peak RSS of a worker {peak:.0f} MB, load {os.getloadavg()[0]:.1f}",
                  flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
