"""Dashboard and session-list speed with 100 patients x 100 sessions (prints numbers; not a test).

    .venv/bin/python bench/dashboard.py [--url postgresql+psycopg://postgres@127.0.0.1:5432/test] [--patients 100]

Fills an empty database (a temporary SQLite file, or a fresh schema on PostgreSQL) with patients, each with
sessions whose metrics documents are real analysis documents of simulated squats (about 7 KB of JSON) and
200 KB files, then times: the summary of every patient in one call, the summary endpoint once per patient,
one page of the session list, and one patient's progress series. Median of 5 runs each.
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import statistics
import sys
import tempfile
import time
import uuid
from collections.abc import Callable
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from sqlalchemy import Engine, create_engine, insert, text  # noqa: E402
from sqlalchemy.orm import Session  # noqa: E402

from backend.database import import_all_models, make_engine, utcnow  # noqa: E402
from backend.exercises.models import Exercise  # noqa: E402
from backend.exercises.service import sync_exercise_library  # noqa: E402
from backend.migrate import upgrade  # noqa: E402
from backend.session_review import dashboard  # noqa: E402
from backend.sessions import service  # noqa: E402
from backend.sessions.models import ExerciseSession, SessionMetric  # noqa: E402
from backend.users.models import User  # noqa: E402
from kinect_agent.analysis.exercise import EXERCISES  # noqa: E402
from kinect_agent.analysis.indicators import indicators  # noqa: E402
from kinect_agent.analysis.report import analyze_recording  # noqa: E402
from kinect_agent.sources.simulator import simulate  # noqa: E402

FILE_BYTES = 200_000


def _engine(url: str | None) -> tuple[Engine, Callable[[], None]]:
    """Returns (engine on an empty schema of url, or on a temporary SQLite file; the cleanup callable)."""
    if url and url.startswith("postgresql"):
        schema = f"bench_dashboard_{os.getpid()}"
        admin = create_engine(url, isolation_level="AUTOCOMMIT")
        with admin.connect() as conn:
            conn.execute(text(f'CREATE SCHEMA "{schema}"'))

        def cleanup() -> None:
            with admin.connect() as conn:
                conn.execute(text(f'DROP SCHEMA "{schema}" CASCADE'))

        return create_engine(url, connect_args={"options": f"-csearch_path={schema}"}), cleanup
    path = Path(tempfile.mkdtemp()) / "bench.db"
    return make_engine(f"sqlite:///{path}"), lambda: path.unlink()


def _fill(engine: Engine, n_patients: int, n_sessions: int) -> list[int]:
    """Adds n_patients patients with n_sessions analysed sessions each; returns the patients' ids."""
    measured, truth, _ = simulate("squat", 5, seed=1)
    report = analyze_recording(measured, EXERCISES["squat"], filtered=truth)
    found = indicators(report, exercise=EXERCISES["squat"], target_reps=10, history=[])
    doc = report.model_dump(mode="json") | {"indicators": found.model_dump(mode="json"), "analysis_version": "bench"}
    blob = os.urandom(FILE_BYTES)
    now = utcnow()
    with Session(engine) as s, s.begin():
        sync_exercise_library(db_session=s)
        exercise_id = s.query(Exercise.id).filter(Exercise.slug == "squat").scalar()
        users = [{"email": f"p{i}@bench.org", "role": "patient", "full_name": f"P{i}"} for i in range(n_patients)]
        ids = [row.id for row in s.execute(insert(User).returning(User.id), users)]
    for pid in ids:
        with Session(engine) as s, s.begin():
            rows = [
                {
                    "client_session_id": uuid.uuid4(),
                    "patient_id": pid,
                    "exercise_id": exercise_id,
                    "started_at": now - dt.timedelta(hours=12 * k),
                    "duration_s": 30.0,
                    "n_frames": 900,
                    "file_bytes": blob,
                    "file_size": FILE_BYTES,
                    "content_hash": "0" * 64,
                    "created_at": now,
                }
                for k in range(n_sessions)
            ]
            sids = [r.id for r in s.execute(insert(ExerciseSession).returning(ExerciseSession.id), rows)]
            s.execute(
                insert(SessionMetric),
                [
                    {"session_id": sid, "document": doc, "repetitions": 5, "rom_deg": 90.0, "quality_ok": True}
                    for sid in sids
                ],
            )
    return ids


def _median_ms(fn: Callable[[], object], runs: int = 5) -> float:
    """Returns the median milliseconds of `runs` calls of fn."""
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return 1000 * statistics.median(times)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--url", default=None, help="PostgreSQL URL (default: a temporary SQLite file)")
    parser.add_argument("--patients", type=int, default=100)
    parser.add_argument("--sessions", type=int, default=100)
    args = parser.parse_args(argv)
    import_all_models()
    engine, cleanup = _engine(args.url)
    try:
        with engine.begin() as conn:
            upgrade(conn, "head")
        start = time.perf_counter()
        ids = _fill(engine, args.patients, args.sessions)
        print(
            f"database: {engine.dialect.name}; filled {len(ids)} x {args.sessions} sessions "
            f"in {time.perf_counter() - start:.1f} s"
        )
        with Session(engine) as s:
            now = utcnow()
            all_ms = _median_ms(lambda: dashboard.summaries(db_session=s, patient_ids=ids, now=now))
            each_ms = _median_ms(
                lambda: [dashboard.summaries(db_session=s, patient_ids=[pid], now=now) for pid in ids], runs=3
            )
            page_ms = _median_ms(
                lambda: service.list_sessions(
                    db_session=s, visible=None, patient_id=None, exercise_id=None, since=None, limit=50, offset=0
                )
            )
            progress_ms = _median_ms(
                lambda: dashboard.progress(db_session=s, patient_id=ids[0], exercise_id=None, since=None)
            )
        print(f"summaries of all {len(ids)} patients in one call: {all_ms:.1f} ms")
        print(f"summary endpoint query, once per patient ({len(ids)} calls): {each_ms:.1f} ms total")
        print(f"session list, first page of 50 of {len(ids) * args.sessions}: {page_ms:.1f} ms")
        print(f"progress of one patient ({args.sessions} points): {progress_ms:.1f} ms")
    finally:
        engine.dispose()
        cleanup()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
