"""A crowd of simultaneous requests spread over every endpoint and role (prints numbers; not a test).

    .venv/bin/python bench/crowd_all.py [--db URL] [--workers 2] [--crowd 300] [--json OUT]

bench/crowd.py sends one therapist's two pages; this one sends what a clinic's server sees at once: the admin's,
the therapists', the patients' and the home agents' requests, every GET of the API whose parameters the demo clinic
fills (lists, details, exports, plots, the PDF report, the data archive, the replay) plus session uploads by devices,
with some event streams held open meanwhile. Setup (not measured): the demo clinic (`coach-server migrate`,
`seed-demo`) in a SQLite file, or in the PostgreSQL database of --db (dropped and recreated; its name must contain
"bench"); the real server (uvicorn, --workers processes); every demo patient's paired device uploads two sessions.
A `coach-server worker` runs beside the server, as in production, and one patient's device uploads a longer
session (LONG_MINUTES) whose four exports are in the staff's mix (past the limits of an export built in the
request: prepared by the worker). Then the crowd leaves at once, request i taking the i-th entry of the mix
(cycled). Reported: answers by status, each 5xx with its path, per role the median and 99th percentile of the
time to the answer; then the build work the 202 answers put off: every distinct request answered 202 is asked
again every 2 s until it answers 200 (when each was ready), and the worker's CPU time and peak memory over the
crowds until the last was ready. The run fails (exit 1) on any 5xx, failed connection, or 202 that never turned
into a 200.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections import Counter, defaultdict
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from backend.demo import ADMIN, DEMO_PASSWORD, PATIENTS, THERAPISTS  # noqa: E402
from bench.crowd import demo_clinic  # noqa: E402
from bench.dashboard_load import ROOT, free_port, start_server, stop_server  # noqa: E402
from bench.ingest import session_file, with_new_session_id  # noqa: E402
from bench.worst_file import ProcessMeter  # noqa: E402

OPEN_STREAMS = 20  # event streams held open by patients' pages during the crowd
SESSION_MINUTES = 0.5  # the uploaded sessions' length
LONG_MINUTES = 6.0  # one longer session, past the server's limits for exports built in the request
DRAIN_S = 900.0  # the longest wait for the worker to prepare what the crowd was told "being prepared"


@dataclass
class Caller:
    """One signed-in role: its client (cookie login or device token) and the paths it asks for."""

    role: str
    client: httpx.AsyncClient
    gets: list[str]


def _sign_in(base: str, email: str) -> dict[str, str]:
    """Returns the login cookies of a demo user."""
    r = httpx.post(f"{base}/api/v1/auth/login", json={"email": email, "password": DEMO_PASSWORD}, timeout=60)
    r.raise_for_status()
    return dict(r.cookies)


def _pair_devices(base: str, admin: dict[str, str]) -> dict[int, str]:
    """Pairs a device with every demo patient; returns {patient id: device token}."""
    with httpx.Client(base_url=base, cookies=admin, timeout=60) as c:
        csrf = {"X-CSRF-Token": c.get("/api/v1/auth/csrf").json()["csrf_token"]}
        patients = c.get("/api/v1/patients", params={"limit": 100}).json()["items"]
        tokens = {}
        for p in patients:
            code = c.post(f"/api/v1/patients/{p['id']}/pairing-codes", headers=csrf).json()["code"]
            r = httpx.post(f"{base}/api/v1/devices/pair", json={"code": code, "name": "crowd"}, timeout=60)
            r.raise_for_status()
            tokens[p["id"]] = r.json()["token"]
    return tokens


def _upload(base: str, token: str, data: bytes) -> int:
    headers = {"Authorization": f"Bearer {token}", "Content-Type": "application/octet-stream"}
    r = httpx.post(f"{base}/api/v1/sessions?exercise=squat", content=with_new_session_id(data), headers=headers,
                   timeout=120)  # fmt: skip
    r.raise_for_status()
    return r.json()["id"]


def _ids(base: str, cookies: dict[str, str]) -> tuple[int, int, int | None]:
    """Returns (a patient id, one of that patient's sessions, one of their plans) visible to the caller."""
    with httpx.Client(base_url=base, cookies=cookies, timeout=60) as c:
        pid = c.get("/api/v1/patients").json()["items"][0]["id"]
        sid = c.get("/api/v1/sessions", params={"patient_id": pid, "limit": 1}).json()["items"][0]["id"]
        plans = c.get(f"/api/v1/patients/{pid}/plans").json()
        plans = plans["items"] if isinstance(plans, dict) else plans
        return pid, sid, (plans[0]["id"] if plans else None)


def _staff_gets(pid: int, sid: int, plan: int | None, long_sid: int) -> list[str]:
    s, p = f"/api/v1/sessions/{sid}", f"/api/v1/patients/{pid}"
    exports = [f"/api/v1/sessions/{long_sid}/export?format={f}" for f in ("csv", "trc", "bvh", "fhir")]
    gets = ["/api/v1/dashboard", "/api/v1/patients", p, f"{p}/therapists", f"{p}/devices", f"{p}/plans",
            f"/api/v1/sessions?patient_id={pid}", s, f"{s}/detail", f"{s}/export?format=csv", f"{s}/file",
            f"{s}/metric-versions", f"{s}/feeling", f"{s}/replay", f"{p}/progress", f"{p}/summary",
            f"{p}/suggestions", f"{p}/voice", f"{p}/report.pdf", f"/api/v1/live/status?patient_id={pid}",
            "/api/v1/exercises", "/api/v1/exercises/squat", "/api/v1/exercises/squat/demonstration",
            "/api/v1/users/me", "/api/v1/version"]  # fmt: skip
    return gets + exports + ([f"/api/v1/plans/{plan}"] if plan else [])


def _patient_gets(pid: int, sid: int) -> list[str]:
    p = f"/api/v1/patients/{pid}"
    return ["/api/v1/users/me", f"{p}/plans", "/api/v1/sessions", f"/api/v1/sessions/{sid}", f"{p}/progress",
            f"{p}/suggestions", f"/api/v1/live/status?patient_id={pid}", "/api/v1/camera/consent", f"{p}/voice",
            f"{p}/archive", "/api/v1/exercises/elbow_flexion/demonstration"]  # fmt: skip


def setup(base: str, session: bytes, long_session: bytes) -> list[Caller]:
    """Signs in one caller per role, pairs devices and uploads sessions (and one long session of the therapist's
    first patient); returns the callers."""
    admin = _sign_in(base, ADMIN[0])
    tokens = _pair_devices(base, admin)
    for token in tokens.values():
        for _ in range(2):
            _upload(base, token, session)
    therapist = _sign_in(base, THERAPISTS[0][0])
    patient = _sign_in(base, PATIENTS[0][0])
    pid, sid, plan = _ids(base, therapist)
    long_sid = _upload(base, tokens[pid], long_session)
    with httpx.Client(base_url=base, cookies=patient, timeout=60) as c:
        own_pid = c.get("/api/v1/users/me").json()["id"]
        own_sid = c.get("/api/v1/sessions", params={"limit": 1}).json()["items"][0]["id"]
    device_token = tokens[own_pid]
    limits = httpx.Limits(max_connections=1000, max_keepalive_connections=1000)

    def client(cookies: dict[str, str] | None = None, headers: dict[str, str] | None = None) -> httpx.AsyncClient:
        return httpx.AsyncClient(base_url=base, timeout=300, limits=limits, cookies=cookies, headers=headers)

    callers = [
        Caller("admin", client(cookies=admin),
               ["/api/v1/users", "/api/v1/audit", *_staff_gets(pid, sid, plan, long_sid)]),
        Caller("therapist", client(cookies=therapist), _staff_gets(pid, sid, plan, long_sid)),
        Caller("patient", client(cookies=patient), _patient_gets(own_pid, own_sid)),
        Caller("device", client(headers={"Authorization": f"Bearer {device_token}"}),
               ["/api/v1/devices/me", f"/api/v1/patients/{own_pid}/plans", "POST /api/v1/sessions?exercise=squat"]),
    ]  # fmt: skip
    return callers


async def crowd(callers: list[Caller], n: int, session: bytes) -> dict[str, Any]:
    """Sends n requests at once (the mix of every caller's requests, cycled) while OPEN_STREAMS event streams are
    open; returns the answers by status, the 5xx with their paths and per-role latencies (s)."""
    mix = [(c, c.gets[k]) for k in range(max(len(c.gets) for c in callers)) for c in callers if k < len(c.gets)]
    patient = next(c for c in callers if c.role == "patient")
    latencies: dict[str, list[float]] = defaultdict(list)
    answers: Counter[str] = Counter()
    errors: list[str] = []
    preparing: dict[tuple[str, str], Caller] = {}  # (role, path) answered 202: a worker prepares it

    async def hold_stream() -> None:
        try:
            async with patient.client.stream("GET", "/api/v1/events", timeout=httpx.Timeout(300, read=None)) as r:
                async for _ in r.aiter_lines():
                    pass
        except (httpx.HTTPError, asyncio.CancelledError):
            pass

    async def one(i: int) -> None:
        caller, path = mix[i % len(mix)]
        t0 = time.perf_counter()
        try:
            if path.startswith("POST "):
                r = await caller.client.post(path[5:], content=with_new_session_id(session),
                                             headers={"Content-Type": "application/octet-stream"})  # fmt: skip
            else:
                r = await caller.client.get(path)
            status = str(r.status_code)
        except httpx.HTTPError as exc:
            status = type(exc).__name__
        latencies[caller.role].append(time.perf_counter() - t0)
        answers[status] += 1
        if status == "202":
            preparing[(caller.role, path)] = caller
        if not status.isdigit() or status.startswith("5"):
            errors.append(f"{status} {caller.role} {path}")

    streams = [asyncio.create_task(hold_stream()) for _ in range(OPEN_STREAMS)]
    await asyncio.sleep(1.0)
    t0 = time.perf_counter()
    await asyncio.gather(*(one(i) for i in range(n)))
    wall = time.perf_counter() - t0
    for task in streams:
        task.cancel()
    await asyncio.gather(*streams, return_exceptions=True)
    per_role = {role: {"n": len(v), "p50_s": round(statistics.median(v), 2),
                       "p99_s": round(sorted(v)[min(len(v) - 1, int(0.99 * len(v)))], 2)}
                for role, v in latencies.items()}  # fmt: skip
    built = await drain(preparing, t0)
    errors += built.pop("errors")
    return {"n": n, "distinct_requests": len(mix), "answers": dict(answers), "errors": errors,
            "last_s": round(wall, 1), "per_role": per_role, "builds": built}  # fmt: skip


async def drain(preparing: dict[tuple[str, str], Caller], t0: float) -> dict[str, Any]:
    """Asks again every 2 s for each distinct request the crowd was answered 202 (a worker prepares it) until it
    answers something else; returns how many, when each was ready (s since the crowd left: median, last) and the
    failures (not 200, or still 202 after DRAIN_S)."""
    ready: list[float] = []
    errors: list[str] = []

    async def one(role: str, path: str, caller: Caller) -> None:
        while True:
            try:
                r = await caller.client.get(path)
                status = str(r.status_code)
            except httpx.HTTPError as exc:
                status = type(exc).__name__
            if status != "202":
                break
            if time.perf_counter() - t0 > DRAIN_S:
                break
            await asyncio.sleep(2.0)
        ready.append(time.perf_counter() - t0)
        if status != "200":
            errors.append(f"{status} {role} {path} (after its build)")

    await asyncio.gather(*(one(role, path, c) for (role, path), c in preparing.items()))
    return {"prepared": len(preparing), "ready_p50_s": round(statistics.median(ready), 1) if ready else 0.0,
            "ready_last_s": round(max(ready), 1) if ready else 0.0, "errors": errors}  # fmt: skip


async def _run(callers: list[Caller], sizes: list[int], session: bytes) -> list[dict[str, Any]]:
    try:
        return [await crowd(callers, n, session) for n in sizes]
    finally:
        for c in callers:
            await c.client.aclose()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--db", help="PostgreSQL URL of a database whose name contains 'bench' (default: SQLite)")
    parser.add_argument("--workers", type=int, default=2, help="server worker processes (default 2)")
    parser.add_argument("--crowd", type=int, nargs="+", default=[300], help="crowd sizes (default 300)")
    parser.add_argument("--json", type=Path, help="also write the numbers to this JSON file")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        url = demo_clinic(args.db, Path(tmp))
        session = session_file(SESSION_MINUTES, Path(tempfile.gettempdir()))
        long_session = session_file(LONG_MINUTES, Path(tempfile.gettempdir()))
        port = free_port()
        server = start_server(url, port, workers=args.workers)
        env = {**os.environ, "COACH_DATABASE_URL": url, "COACH_ENVIRONMENT": "local"}
        worker = subprocess.Popen([str(Path(sys.executable).parent / "coach-server"), "worker"], env=env, cwd=ROOT,
                                  stderr=subprocess.DEVNULL)  # fmt: skip
        try:
            callers = setup(f"http://127.0.0.1:{port}", session, long_session)
            meter = ProcessMeter(worker.pid)
            meter.start()
            rows = asyncio.run(_run(callers, args.crowd, session))
            cpu, peak = meter.stop()  # every crowd's builds, until the last was ready
        finally:
            worker.terminate()
            worker.wait(timeout=600)
            stop_server(server)
    for row in rows:
        answers = ", ".join(f"{k}: {v}" for k, v in sorted(row["answers"].items()))
        print(f"crowd {row['n']} over {row['distinct_requests']} distinct requests, {args.workers} workers: {answers};"
              f" last answer after {row['last_s']} s")  # fmt: skip
        for role, r in row["per_role"].items():
            print(f"  {role:<10} {r['n']:>4} requests  p50 {r['p50_s']:>6.2f} s  p99 {r['p99_s']:>6.2f} s")
        b = row["builds"]
        print(f"  prepared by the worker: {b['prepared']} distinct requests answered 202, ready after "
              f"{b['ready_p50_s']} s (median) / {b['ready_last_s']} s (last)")  # fmt: skip
        for line in row["errors"]:
            print(f"  error: {line}")
    print(f"worker: {cpu:.1f} s CPU, peak {peak / 2**20:.0f} MiB above its start, over every crowd until the last "
          f"build was ready")  # fmt: skip
    if args.json:
        args.json.write_text(json.dumps({"crowds": rows, "worker": {"cpu_s": round(cpu, 1),
                                         "peak_mib": round(peak / 2**20)}}, indent=2))  # fmt: skip
    return 1 if any(r["errors"] for r in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
