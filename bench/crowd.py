"""A crowd of simultaneous API requests against one server process (prints numbers; not a test).

    .venv/bin/python bench/crowd.py [--db URL] [--crowd 60 300] [--json OUT]

Setup (not measured): the demo clinic (`coach-server migrate` and `seed-demo`) in a SQLite file in a temp folder,
or in the PostgreSQL database of --db (dropped and recreated; its name must contain "bench"); the real server in a
subprocess (bench.dashboard_load.start_server: uvicorn, one worker, defaults otherwise). One therapist signs in
(cookie session); then, for each crowd size N, N requests leave at once (half GET /api/v1/dashboard, half
GET /api/v1/patients) and the answers are counted by status, with the time until the last one. What it measures:
whether a crowd larger than the worker's threads (40) plus its pooled connections (5 + 10) is answered
(backend/db_slots.py) or starves the pool (500 after the pool's 30 s timeout).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path
from typing import TypedDict

import httpx
from sqlalchemy.engine import make_url

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from backend.demo import DEMO_PASSWORD  # noqa: E402
from bench.dashboard_load import ROOT, free_port, migrate, recreate_database, start_server, stop_server  # noqa: E402

THERAPIST = "physio@demo.clinic"


class Crowd(TypedDict):
    """One crowd: its size, the count of each answer (status code or error name), seconds to the last answer."""

    n: int
    answers: dict[str, int]
    last_s: float


async def one_crowd(base: str, n: int) -> Crowd:
    """Sends n requests at once as the demo therapist; returns {"n", "answers": {status: count}, "last_s"}."""
    async with httpx.AsyncClient(base_url=base, timeout=120, limits=httpx.Limits(max_connections=n)) as client:
        login = await client.post("/api/v1/auth/login", json={"email": THERAPIST, "password": DEMO_PASSWORD})
        login.raise_for_status()

        async def request(i: int) -> str:
            try:
                return str((await client.get("/api/v1/patients" if i % 2 else "/api/v1/dashboard")).status_code)
            except httpx.HTTPError as exc:
                return type(exc).__name__

        t0 = time.perf_counter()
        answers = await asyncio.gather(*(request(i) for i in range(n)))
        return {"n": n, "answers": dict(Counter(answers)), "last_s": round(time.perf_counter() - t0, 2)}


def demo_clinic(db: str | None, tmp: Path) -> str:
    """Returns the URL of a database holding the demo clinic (`coach-server migrate`, `seed-demo`): the PostgreSQL
    database db (dropped and recreated; its name must contain "bench"), or with db None a SQLite file in tmp."""
    url = db or f"sqlite:///{tmp / 'crowd.db'}"
    if db:
        if "bench" not in (make_url(url).database or ""):
            raise SystemExit(f"--db {url}: the database is dropped and recreated; its name must contain 'bench'")
        recreate_database(url)
    migrate(url)
    env = {**os.environ, "COACH_DATABASE_URL": url}
    subprocess.run([str(Path(sys.executable).parent / "coach-server"), "seed-demo"], env=env, check=True, cwd=ROOT,
                   stdout=subprocess.DEVNULL)  # fmt: skip
    return url


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--db", help="PostgreSQL URL of a database whose name contains 'bench' (default: SQLite)")
    parser.add_argument("--crowd", type=int, nargs="+", default=[60, 300], help="crowd sizes (default 60 300)")
    parser.add_argument("--json", type=Path, help="also write the numbers to this JSON file")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        url = demo_clinic(args.db, Path(tmp))
        port = free_port()
        server = start_server(url, port, workers=1)
        try:
            rows = [asyncio.run(one_crowd(f"http://127.0.0.1:{port}", n)) for n in args.crowd]
        finally:
            stop_server(server)
    print(f"{'crowd':>6}  {'answers':<40} {'last answer':>11}")
    for row in rows:
        answers = ", ".join(f"{k}: {v}" for k, v in sorted(row["answers"].items()))
        print(f"{row['n']:>6}  {answers:<40} {row['last_s']:>9.1f} s")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=2))
    return 0 if all(set(r["answers"]) == {"200"} for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
