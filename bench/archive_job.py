"""The patient's archive: what its request costs when it builds the zip, against asking a worker (prints numbers).

    .venv/bin/python -m bench.archive_job [--sessions 50] [--reps 30] [--repeats 5] [--database-url URL] [--rss 3]

Migrates a new database (default: a SQLite file in a temporary folder; a PostgreSQL URL's public schema is emptied
first), uploads --sessions simulated squat sets of --reps repetitions for one patient through the ASGI app (as the
home agent does: the server analyses and stores each), then times, in this process (wall and CPU seconds, median of
--repeats):
  * a tree whose GET /patients/{id}/archive answers 200 (the zip built in the request, before this branch): that
    GET, --repeats times;
  * a tree where it answers 202 (the worker builds it): the first ask (POST, queues the job), a repeated ask, GET
    .../archive/status, the worker's build of the job (backend.jobs.worker.work, --builds times, the kept archive
    dropped before each), and the download of the kept zip;
  * with --rss N, first N builds each in a worker process of its own (this script run with --child-build: the
    modules imported, its peak resident set reset through /proc/self/clear_refs, then one job): the process's
    resident set before the job and its peak during it (VmRSS, VmHWM; MiB), and the growth, the build's own memory.
Run from the tree to measure (`cd /work/main && PYTHONPATH=$PWD python /path/to/bench/archive_job.py` for main).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, TypeVar

import sqlalchemy as sa
from fastapi.testclient import TestClient
from sqlalchemy.orm import Session, sessionmaker

if TYPE_CHECKING:
    from backend.config import Settings

T = TypeVar("T")
ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))


def _timed(fn: Callable[[], T]) -> tuple[float, float, T]:
    """Returns (wall s, CPU s of this process, fn's result)."""
    w0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return time.perf_counter() - w0, time.process_time() - c0, out


def _median(rows: list[tuple[float, float]]) -> str:
    return f"{statistics.median(r[0] for r in rows):.3f} s wall / {statistics.median(r[1] for r in rows):.3f} s CPU"


def _engine(url: str) -> sa.Engine:
    from backend.database import import_all_models, make_engine
    from backend.migrate import upgrade

    import_all_models()
    engine = make_engine(url)
    if url.startswith("postgresql"):
        with engine.begin() as conn:
            conn.execute(sa.text("DROP SCHEMA public CASCADE; CREATE SCHEMA public"))
    with engine.begin() as conn:
        upgrade(conn, "head")
    return engine


def _status_mib(field: str) -> float:
    """Returns one memory line of /proc/self/status (VmRSS, VmHWM) in MiB."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1]) / 1024
    raise RuntimeError(f"no {field} in /proc/self/status")


def _child_build(url: str, storage_dir: str) -> None:
    """Runs one archive job of the database at url, as `coach-server worker --once` would, and prints the resident
    set before it and its peak during it (JSON, MiB)."""
    import json

    from backend.config import Settings
    from backend.database import import_all_models, make_engine
    from backend.jobs.worker import work
    from backend.main import create_app  # noqa: F401 - every module a job imports, imported before the reset
    from backend.records import archive, prepared_archive  # noqa: F401
    from backend.storage import use_store
    from backend.storage.local import LocalStore

    import_all_models()
    use_store(LocalStore(storage_dir))
    settings = Settings(ENVIRONMENT="local", CHECK_MIGRATIONS=False, DATABASE_URL=url, STORAGE_DIR=storage_dir)
    make = sessionmaker(make_engine(url), expire_on_commit=False)
    Path("/proc/self/clear_refs").write_text("5")  # VmHWM := VmRSS now (Linux): the peak of what follows
    before = _status_mib("VmRSS")
    ran = work(sessionmaker=make, settings=settings, name="bench-rss", once=True, kinds=("archive",))
    print(json.dumps({"ran": ran, "before_mib": before, "peak_mib": _status_mib("VmHWM")}))


def _rss_builds(base: str, headers: dict[str, str], client: TestClient, make: Callable[[], Session], url: str,
                storage_dir: str, n: int) -> None:  # fmt: skip
    """Builds the archive n times, each in a worker process of its own; prints its memory."""
    import json
    import subprocess

    from backend.jobs.models import Job
    from backend.records.models import PatientArchive

    rows = []
    for _ in range(n):
        with make() as db:  # drop the kept archive: the next ask builds it again
            db.execute(sa.delete(PatientArchive))
            db.execute(sa.delete(Job).where(Job.kind == "archive"))
            db.commit()
        assert client.post(base, headers=headers).status_code == 202
        done = subprocess.run([sys.executable, __file__, "--child-build", url, storage_dir], capture_output=True,
                              text=True, check=True, env=os.environ | {"PYTHONPATH": os.getcwd()})  # fmt: skip
        got = json.loads(done.stdout.strip().splitlines()[-1])
        assert got["ran"] == 1, got
        rows.append((got["before_mib"], got["peak_mib"]))
    with make() as db:  # as before: the job queued by one ask, no archive kept
        db.execute(sa.delete(PatientArchive))
        db.execute(sa.delete(Job).where(Job.kind == "archive"))
        db.commit()
    assert client.post(base, headers=headers).status_code == 202
    grew = [peak - before for before, peak in rows]
    print(
        f"worker process, one build: resident before {statistics.median(r[0] for r in rows):.0f} MiB, peak "
        f"{statistics.median(r[1] for r in rows):.0f} MiB, growth {statistics.median(grew):.0f} MiB (median of {n}; "
        f"runs {', '.join(f'{g:.0f}' for g in grew)} MiB)"
    )


def main() -> None:
    if sys.argv[1:2] == ["--child-build"]:
        _child_build(sys.argv[2], sys.argv[3])
        return
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sessions", type=int, default=50)
    ap.add_argument("--reps", type=int, default=30)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--builds", type=int, default=3)
    ap.add_argument("--database-url", default="")
    ap.add_argument("--rss", type=int, default=0, help="builds in a worker process of its own, memory measured")
    args = ap.parse_args()

    from backend.config import Settings, get_settings
    from backend.database import db_dependency, get_db
    from backend.exercises.service import sync_exercise_library
    from backend.main import create_app
    from backend.storage import use_store
    from backend.storage.local import LocalStore
    from backend.users.service import create_api_token, create_user
    from tests.backend.khs_files import make_khs

    tmp = Path(tempfile.mkdtemp(prefix="bench-archive-"))
    url = args.database_url or f"sqlite:///{tmp / 'bench.db'}"
    engine = _engine(url)
    use_store(LocalStore(tmp / "objects"))
    settings = Settings(ENVIRONMENT="local", CHECK_MIGRATIONS=False, DATABASE_URL=url, STORAGE_DIR=str(tmp / "objects"),
                        EVENTS_STREAM_MAX_S=0.0, LIVE_WARM_UP=False)  # fmt: skip
    make = sessionmaker(engine, expire_on_commit=False)
    with make() as db:
        sync_exercise_library(db_session=db)
        patient = create_user(db_session=db, email="bench@example.org", password=None, role="patient")
        _, token = create_api_token(db_session=db, user=patient, name="bench", scopes=["read", "write"], days=1)
        db.commit()
    headers = {"Authorization": f"Bearer {token}"}
    app = create_app(settings)
    app.dependency_overrides[get_db] = db_dependency(engine)
    app.dependency_overrides[get_settings] = lambda: settings
    client = TestClient(app, raise_server_exceptions=True)
    t0 = time.perf_counter()
    for seed in range(args.sessions):
        r = client.post("/api/v1/sessions", content=make_khs("squat", args.reps, seed=1000 + seed),
                        headers={"Content-Type": "application/octet-stream", **headers},
                        params={"exercise": "squat"})  # fmt: skip
        assert r.status_code == 201, r.text
    took = time.perf_counter() - t0
    print(f"{args.sessions} sessions of {args.reps} squats uploaded in {took:.0f} s ({url.split(':')[0]})")
    base = f"/api/v1/patients/{patient.id}/archive"
    wall, cpu, first = _timed(lambda: client.get(base, headers=headers))
    if first.status_code == 200:  # the zip built in the request
        rows = [(wall, cpu)] + [_timed(lambda: client.get(base, headers=headers))[:2] for _ in range(args.repeats - 1)]
        print(
            f"GET archive, built in the request: {_median(rows)}; {len(first.content) / 2**20:.1f} MiB; "
            f"runs {', '.join(f'{w:.2f}' for w, _ in rows)} s"
        )
        return
    assert first.status_code == 202, first.text
    if args.rss:
        _rss_builds(base, headers, client, make, url, str(tmp / "objects"), args.rss)
    _after(client, base, headers, make, settings, args, (wall, cpu))


def _after(client: TestClient, base: str, headers: dict[str, str], make: Callable[[], Session], settings: Settings,
           args: argparse.Namespace, first_get: tuple[float, float]) -> None:  # fmt: skip
    from backend.jobs.models import Job
    from backend.jobs.worker import work
    from backend.records.models import PatientArchive

    asks = [_timed(lambda: client.post(base, headers=headers))[:2] for _ in range(args.repeats)]
    status = [_timed(lambda: client.get(f"{base}/status", headers=headers))[:2] for _ in range(args.repeats)]
    print(f"first ask (GET, queues the job): {first_get[0]:.3f} s wall / {first_get[1]:.3f} s CPU")
    print(f"asked again (POST, already queued): {_median(asks)}")
    print(f"status: {_median(status)}")
    builds = []
    for i in range(args.builds):
        if i:
            with make() as db:  # drop the kept archive: the next ask builds it again
                db.execute(sa.delete(PatientArchive))
                db.execute(sa.delete(Job).where(Job.kind == "archive"))
                db.commit()
            assert client.post(base, headers=headers).status_code == 202
        wall, cpu, ran = _timed(lambda: work(sessionmaker=make, settings=settings, name="bench", once=True,
                                             kinds=("archive",)))  # fmt: skip
        assert ran == 1, ran
        builds.append((wall, cpu))
    state = client.get(f"{base}/status", headers=headers).json()
    assert state["state"] == "ready", state
    got = [_timed(lambda: client.get(state["download_url"], headers=headers)) for _ in range(args.repeats)]
    assert all(r[2].status_code == 200 for r in got)
    print(
        f"worker build: {_median(builds)}; runs {', '.join(f'{w:.2f}' for w, _ in builds)} s; "
        f"{state['size'] / 2**20:.1f} MiB, {state['sessions']} sessions, {state['incomplete']} incomplete"
    )
    print(f"download of the kept zip: {_median([r[:2] for r in got])}")


if __name__ == "__main__":
    main()
