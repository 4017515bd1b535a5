"""The live loop under load: latency from the agent's frame to the patient's browser showing it, and the server's
memory and CPU with 200 patient pages connected (prints numbers; not a test).

    .venv/bin/python bench/live.py [--db URL | --sqlite] [--workers 2] [--messages 1000] [--rate 10]
                                   [--pages 200] [--agents 20] [--quick] [--json OUT]

Setup (not measured): a fresh database (PostgreSQL: drops and recreates the database of --db; --sqlite: a temp
file, one worker), migrated with `coach-server migrate`; --pages patients, each with a paired device and an API
token; the real server (uvicorn, backend.main:create_app, --workers N) on a free port.

1. Latency, quiet: one headless Chromium (Debian's /usr/bin/chromium) signs in as patient 0 through the login
   form and opens their page. An agent thread sends --messages progress messages through the agent's own
   Publisher (kinect_agent/live/channel.py) at --rate Hz, each stamped with the wall clock when its "frame" is
   taken. The page records Date.now() − sent_at when it has drawn each one (live.js dispatches
   `coach-live-shown` after drawing). Same machine, same clock.
2. Load: --pages event streams (`GET /api/v1/events?patient_id=..&live=true`, what a patient page holds open;
   light HTTP clients with the patients' API tokens, not 200 browsers) connect, then --agents other patients'
   agents post progress at 5 Hz each. Reported: the server's RSS (master + workers, /proc VmRSS) before and
   after the pages connect; its CPU (utime + stime, /proc) per second idle with the pages connected and while
   the agents post; the latency of step 1 again, under this load.
PASS when p95 ≤ --target-ms (250) in both latency runs and no message is lost to an error.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import sys
import tempfile
import threading
import time
import uuid
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import httpx  # noqa: E402
from sqlalchemy import create_engine  # noqa: E402
from sqlalchemy.orm import Session  # noqa: E402

from bench.dashboard_load import free_port, migrate, percentile, recreate_database, start_server, stop_server  # noqa: E402

DEFAULT_DB = "postgresql+psycopg://postgres@127.0.0.1:5432/coach_bench_live"
PASSWORD = "bench-password-2026"
CHROMIUM = "/usr/bin/chromium"


def seed(url: str, n_patients: int) -> list[dict]:
    """Creates n patients with a device token and an API token each; returns [{id, email, device, api}]."""
    from backend.database import import_all_models
    from backend.devices.models import Device
    from backend.security import DEVICE_TOKEN_PREFIX, hash_password, new_token, token_hash
    from backend.users.models import User
    from backend.users.service import create_api_token

    import_all_models()
    engine = create_engine(url)
    password_hash = hash_password(PASSWORD)  # one hash for all: argon2 costs 0.8 s each
    out = []
    with Session(engine) as db, db.begin():
        for k in range(n_patients):
            user = User(email=f"live{k}@bench.example", role="patient", full_name=f"Bench Patient {k}",
                        password_hash=password_hash, is_active=True)  # fmt: skip
            db.add(user)
            db.flush()
            device_token = new_token(DEVICE_TOKEN_PREFIX)
            db.add(Device(patient_id=user.id, name=f"bench {k}", token_hash=token_hash(device_token)))
            _, api = create_api_token(db_session=db, user=user, name="bench", scopes=["read"])
            out.append({"id": user.id, "email": user.email, "device": device_token, "api": api})
    engine.dispose()
    return out


def server_pids(master: int) -> list[int]:
    """Returns the server's master pid and its children (the workers)."""
    pids = [master]
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1]) == master:
                    pids.append(int(entry.name))
            except (OSError, IndexError, ValueError):
                continue
    return pids


def rss_mb(pids: list[int]) -> float:
    """Returns the summed resident memory of pids, MB."""
    total = 0
    for pid in pids:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                total += int(line.split()[1])
    return total / 1024


def cpu_s(pids: list[int]) -> float:
    """Returns the summed user + system CPU seconds of pids."""
    tick = os.sysconf("SC_CLK_TCK")
    total = 0
    for pid in pids:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        total += int(fields[11]) + int(fields[12])
    return total / tick


def send_progress(base: str, token: str, n: int, rate: float, stop: threading.Event | None = None) -> dict:
    """Sends n progress messages (or until stop) at rate Hz through the agent's Publisher; returns its counters."""
    from kinect_agent.live.channel import Publisher

    pub = Publisher(base, token, log=lambda _: None)
    set_id, t0 = str(uuid.uuid4()), time.monotonic()
    k = 0
    while k < n and not (stop and stop.is_set()):
        time.sleep(max(0.0, t0 + k / rate - time.monotonic()))
        pub.offer({"set_id": set_id, "exercise_slug": "elbow_flexion", "state": "recording", "count": k % 10_000,
                   "target": 10_000, "angle_name": "elbow_flexion_L", "angle_deg": 45.0, "elapsed_s": k / rate,
                   "sent_at": time.time()})  # fmt: skip
        k += 1
    pub.close()
    return {"offered": k, "sent": pub.sent, "dropped": pub.dropped}


def latency_run(page, base: str, patient: dict, n: int, rate: float) -> dict:
    """Measures frame-to-screen latency of n messages to the open page of patient; returns the statistics."""
    page.evaluate("window.__lat = []; if (!window.__latOn) { window.__latOn = true; addEventListener("
                  "'coach-live-shown', (e) => __lat.push(Date.now() / 1000 - e.detail.sent_at)); }")  # fmt: skip
    counters = send_progress(base, patient["device"], n, rate)
    time.sleep(1.0)
    lat = [1000 * x for x in page.evaluate("window.__lat")]
    return {**counters, "shown": len(lat), "p50_ms": percentile(lat, 50), "p95_ms": percentile(lat, 95),
            "p99_ms": percentile(lat, 99), "max_ms": max(lat, default=float("nan"))}  # fmt: skip


class Pages:
    """n event streams held open in a thread of their own (asyncio), as n open patient pages."""

    def __init__(self, base: str, patients: list[dict]) -> None:
        self.base, self.patients = base, patients
        self.connected = 0
        self.events = 0
        self._stop = threading.Event()
        self._ready = threading.Event()
        self._thread = threading.Thread(target=lambda: asyncio.run(self._main()), daemon=True)

    def open(self, timeout: float = 60.0) -> int:
        """Connects all streams; returns how many connected."""
        self._thread.start()
        self._ready.wait(timeout)
        return self.connected

    def close(self) -> None:
        self._stop.set()
        self._thread.join(timeout=15)

    async def _one(self, client: httpx.AsyncClient, patient: dict) -> None:
        headers = {"Authorization": f"Bearer {patient['api']}"}
        params = {"patient_id": patient["id"], "live": "true"}
        while not self._stop.is_set():
            try:
                async with client.stream("GET", "/api/v1/events", params=params, headers=headers) as r:
                    first = True
                    async for line in r.aiter_lines():
                        if first:
                            self.connected += 1
                            first = False
                        self.events += line.startswith("data:")
                        if self._stop.is_set():
                            return
                    self.connected -= 1  # the stream's lifetime ended: reconnect, as the browser does
            except httpx.HTTPError:
                await asyncio.sleep(1)

    async def _main(self) -> None:
        limits = httpx.Limits(max_connections=len(self.patients) + 10)
        async with httpx.AsyncClient(base_url=self.base, timeout=httpx.Timeout(10, read=None), limits=limits) as c:
            tasks = [asyncio.create_task(self._one(c, p)) for p in self.patients]
            while self.connected < len(self.patients) and not self._stop.is_set():
                await asyncio.sleep(0.2)
            self._ready.set()
            while not self._stop.is_set():
                await asyncio.sleep(0.2)
            for t in tasks:
                t.cancel()


def open_patient_page(browser, base: str, patient: dict):
    """Signs in as the patient through the login form; returns their page once its event stream is up."""
    page = browser.new_context(viewport={"width": 1280, "height": 900}).new_page()
    page.goto(f"{base}/")
    page.fill("#email", patient["email"])
    page.fill("#password", PASSWORD)
    page.click("#login-submit")
    page.wait_for_url(f"{base}/patient")
    page.wait_for_function("document.getElementById('agent-status').dataset.state !== undefined")
    time.sleep(1.0)
    return page


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--db", default=DEFAULT_DB, help=f"PostgreSQL URL (recreated!) (default {DEFAULT_DB})")
    parser.add_argument("--sqlite", action="store_true", help="a temporary SQLite file and one worker instead")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--messages", type=int, default=1000)
    parser.add_argument("--rate", type=float, default=10.0, help="progress messages per second (agent: 5)")
    parser.add_argument("--pages", type=int, default=200)
    parser.add_argument("--agents", type=int, default=20)
    parser.add_argument("--window", type=float, default=20.0, help="CPU measuring window, s")
    parser.add_argument("--target-ms", type=float, default=250.0)
    parser.add_argument("--quick", action="store_true", help="100 messages, 20 pages, 5 agents, 5 s windows")
    parser.add_argument("--json", type=Path, help="write the results here")
    args = parser.parse_args(argv)
    if args.quick:
        args.messages, args.pages, args.agents, args.window = 100, 20, 5, 5.0
    if args.sqlite:
        url, workers = f"sqlite:///{tempfile.mkdtemp(prefix='bench-live-')}/live.db", 1
    else:
        url, workers = args.db, args.workers
        recreate_database(url)
    migrate(url)
    patients = seed(url, max(args.pages, args.agents + 1))
    port = free_port()
    server = start_server(url, port, workers)
    base = f"http://127.0.0.1:{port}"
    from playwright.sync_api import sync_playwright

    results: dict = {"database": "sqlite" if args.sqlite else "postgresql", "workers": workers}
    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=["--no-sandbox"])
            page = open_patient_page(browser, base, patients[0])
            pids = server_pids(server.pid)
            results["rss_mb_start"] = rss_mb(pids)
            results["quiet"] = latency_run(page, base, patients[0], args.messages, args.rate)
            pages = Pages(base, patients[: args.pages])
            results["pages_connected"] = pages.open()
            time.sleep(2.0)
            results["rss_mb_pages"] = rss_mb(server_pids(server.pid))
            c0 = cpu_s(server_pids(server.pid))
            time.sleep(args.window)
            results["cpu_pct_idle_pages"] = 100 * (cpu_s(server_pids(server.pid)) - c0) / args.window
            stop = threading.Event()
            agents = [threading.Thread(target=send_progress, args=(base, p["device"], 10**9, 5.0, stop), daemon=True)
                      for p in patients[1 : args.agents + 1]]  # fmt: skip
            for a in agents:
                a.start()
            c0, t0 = cpu_s(server_pids(server.pid)), time.monotonic()
            results["loaded"] = latency_run(page, base, patients[0], args.messages, args.rate)
            elapsed = time.monotonic() - t0
            results["cpu_pct_agents"] = 100 * (cpu_s(server_pids(server.pid)) - c0) / elapsed
            results["rss_mb_loaded"] = rss_mb(server_pids(server.pid))
            results["events_to_pages"] = pages.events
            stop.set()
            for a in agents:
                a.join(timeout=10)
            pages.close()
            browser.close()
    finally:
        stop_server(server)
    report(results, args)
    if args.json:
        args.json.write_text(json.dumps(results, indent=2))
    ok = all(results[k]["p95_ms"] <= args.target_ms and results[k]["shown"] > 0 for k in ("quiet", "loaded"))
    print("PASS" if ok else "FAIL", f"(p95 target {args.target_ms:.0f} ms)")
    return 0 if ok else 1


def report(r: dict, args: argparse.Namespace) -> None:
    """Prints the results as a table."""
    print(f"\nlive loop on {r['database']}, {r['workers']} worker(s); {args.messages} messages at {args.rate:g} Hz")
    print(f"{'run':<28}{'offered':>8}{'sent':>6}{'shown':>7}{'p50 ms':>8}{'p95 ms':>8}{'p99 ms':>8}{'max ms':>8}")
    for key, label in (("quiet", "quiet"), ("loaded", f"{r['pages_connected']} pages + {args.agents} agents")):
        x = r[key]
        print(f"{label:<28}{x['offered']:>8}{x['sent']:>6}{x['shown']:>7}{x['p50_ms']:>8.1f}{x['p95_ms']:>8.1f}"
              f"{x['p99_ms']:>8.1f}{x['max_ms']:>8.1f}")  # fmt: skip
    print(f"server RSS: {r['rss_mb_start']:.0f} MB at start, {r['rss_mb_pages']:.0f} MB with {r['pages_connected']} "
          f"pages, {r['rss_mb_loaded']:.0f} MB with the agents posting")  # fmt: skip
    print(f"server CPU: {r['cpu_pct_idle_pages']:.1f} % of one core idle with the pages, {r['cpu_pct_agents']:.1f} % "
          f"while {args.agents} agents post 5 messages/s each")  # fmt: skip


if __name__ == "__main__":
    sys.exit(main())
