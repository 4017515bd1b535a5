"""The live loop under load: latency from the agent's frame to the patient's browser showing it, and the server's
memory and CPU with 200 patient pages connected (prints numbers; not a test).

    .venv/bin/python bench/live.py [--db URL | --db sqlite] [--workers 2] [--messages 1000] [--rate 10]
                                   [--pages 200] [--agents 20] [--window 15] [--quick] [--json OUT]

Setup (not measured): a fresh database (PostgreSQL: drops and recreates the database of --db, whose name must
contain "bench"; `--db sqlite`: a SQLite file in a temporary folder and one worker), migrated with
`coach-server migrate`; --pages + 1 patients (password login) with a paired device each (device token, as
`POST /api/v1/devices/pair` makes). The real server in a subprocess: uvicorn backend.main:create_app --workers N
(bench.dashboard_load.start_server), configured only through COACH_DATABASE_URL and COACH_ENVIRONMENT=local, the
defaults otherwise (the event streams' lifetime COACH_EVENTS_STREAM_MAX_S stays 300 s). The --pages light clients
then log in through POST /api/v1/auth/login (cookie sessions, as the browser does).

1. Latency, quiet. One headless Chromium (/usr/bin/chromium) opens /, signs in as patient 0 through the login form
   and lands on their page (/patient), whose scripts open GET /api/v1/events?patient_id=..&live=true. An agent
   process of its own holds the device's command stream (GET /api/v1/live/agent, so the page shows the home
   computer ready) and sends --messages progress messages through the agent's Publisher
   (kinect_agent/live/channel.py) at --rate Hz, each stamped sent_at = time.time() when its "frame" is taken. The
   page's listener of `coach-live-shown` (live.js dispatches it after drawing the count) records
   Date.now() - sent_at; also the time to the next frame after it (requestAnimationFrame then a task). Same
   machine, same clock. Every message is accounted for: coalesced by the Publisher (it keeps only the newest
   unsent one), failed POST, lost while the page's stream reconnected, lost otherwise, or shown.
2. Load. The --pages light clients (httpx, not browsers: one event stream each, what a patient page holds open;
   they do not load the page's data) connect to their own patients' streams; the server's RSS (master + workers,
   /proc VmRSS) is read before and after. CPU (utime + stime from /proc, server processes summed; also the
   PostgreSQL backends of this database) over a --window idle with the pages connected, then over a --window while
   --agents agents (patients 1..agents, whose pages are connected) each hold their command stream and post
   progress at 5 Hz. Then step 1 again (the page reloaded first) with the pages connected and the agents posting.
Streams end after COACH_EVENTS_STREAM_MAX_S: the browser reconnects by itself after the stream's retry delay
(3 s), the light clients do the same; reconnects are counted and messages lost in their gaps reported apart.
PASS when p95 <= --target-ms (250 ms) in both latency runs.
"""

from __future__ import annotations

import argparse
import asyncio
import datetime as dt
import json
import multiprocessing as mp
import os
import statistics
import sys
import tempfile
import threading
import time
import uuid
from collections.abc import Coroutine
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

if TYPE_CHECKING:
    from multiprocessing.queues import Queue
    from multiprocessing.synchronize import Event

    from playwright.sync_api import Browser, Page

    from kinect_agent.live.channel import CommandStream

Result = TypeVar("Result")

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import httpx  # noqa: E402
from sqlalchemy import create_engine  # noqa: E402
from sqlalchemy.engine import make_url  # noqa: E402
from sqlalchemy.orm import Session  # noqa: E402

from bench.dashboard_load import (  # noqa: E402
    free_port,
    migrate,
    percentile,
    recreate_database,
    start_server,
    stop_server,
)

DEFAULT_DB = "postgresql+psycopg://postgres@127.0.0.1:5432/coach_bench_live"
PASSWORD = "bench-password-2026"
CHROMIUM = "/usr/bin/chromium"
EXERCISE = "elbow_flexion"
AGENT_HZ = 5.0  # the agent's progress rate (kinect_agent/live/set_recorder.py, every_s = 0.2)
LOGIN_CONCURRENCY = 8  # light clients logging in at once (argon2 costs ~0.17 s of CPU each)
TAIL_S = 2.0  # wait after the last message before reading the page's records
SETTLE_S = 3.0  # wait after connecting before a measurement window

# Instruments the page before its scripts run: every EventSource's open/error times (ms), for reconnect accounting.
EVENTSOURCE_PROBE = """
(() => {
  const Native = window.EventSource;
  if (!Native) return;
  window.__es = { opens: [], errors: [] };
  window.EventSource = class extends Native {
    constructor(...args) {
      super(...args);
      this.addEventListener("open", () => window.__es.opens.push(Date.now()));
      this.addEventListener("error", () => window.__es.errors.push(Date.now()));
    }
  };
})();
"""
# Records, for each drawn progress message: [sent_at s, Date.now() ms at coach-live-shown, Date.now() ms next frame].
SHOWN_LISTENER = """
() => {
  window.__shown = [];
  if (window.__shownOn) return;
  window.__shownOn = true;
  window.addEventListener("coach-live-shown", (e) => {
    const rec = [e.detail.sent_at, Date.now(), null];
    window.__shown.push(rec);
    requestAnimationFrame(() => setTimeout(() => { rec[2] = Date.now(); }, 0));
  });
}
"""


# ------------------------------------------------------------------------------------------------ setup


def seed(url: str, n_patients: int) -> list[dict[str, Any]]:
    """Creates n patients with a password and a paired device each, each device with a started set (as the
    patient's Start stores it: the server accepts progress only for that set); returns [{id, email, device, set_id}]."""
    from backend.database import import_all_models
    from backend.devices.models import Device
    from backend.security import DEVICE_TOKEN_PREFIX, hash_password, new_token, token_hash
    from backend.users.models import User

    import_all_models()
    engine = create_engine(url)
    password_hash = hash_password(PASSWORD)  # one hash for all: setup, not the measurement
    out = []
    with Session(engine) as db, db.begin():
        for k in range(n_patients):
            user = User(email=f"live{k:03d}@bench.example", role="patient", full_name=f"Bench Patient {k}",
                        password_hash=password_hash, is_active=True)  # fmt: skip
            db.add(user)
            db.flush()
            device_token = new_token(DEVICE_TOKEN_PREFIX)
            set_id = str(uuid.uuid4())
            db.add(Device(patient_id=user.id, name=f"bench {k}", token_hash=token_hash(device_token),
                          live_set_id=set_id))  # fmt: skip
            out.append({"id": user.id, "email": user.email, "device": device_token, "set_id": set_id})
    engine.dispose()
    return out


# ------------------------------------------------------------------------------------------------ /proc


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
    """Returns the summed resident memory (VmRSS) of pids, MB."""
    total = 0
    for pid in pids:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                total += int(line.split()[1])
    return total / 1024


def cpu_of(pids: list[int]) -> dict[int, float]:
    """Returns user + system CPU seconds per pid (pids that are gone are left out)."""
    tick = os.sysconf("SC_CLK_TCK")
    out = {}
    for pid in pids:
        try:
            fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        out[pid] = (int(fields[11]) + int(fields[12])) / tick
    return out


def machine_busy() -> tuple[int, int]:
    """Returns (busy, total) jiffies of all CPUs since boot (/proc/stat)."""
    values = [int(v) for v in Path("/proc/stat").read_text().splitlines()[0].split()[1:]]
    idle = values[3] + values[4]  # idle + iowait
    return sum(values) - idle, sum(values)


class Usage:
    """CPU seconds of the server, of the PostgreSQL backends of its database, of this process and of the machine
    over a window."""

    def __init__(self, master: int, db_url: str) -> None:
        self.master = master
        self.db_url = db_url if make_url(db_url).get_backend_name() == "postgresql" else None

    def _pg_pids(self) -> list[int]:
        if self.db_url is None:
            return []
        import psycopg

        from backend.events.listener import conninfo

        url = make_url(self.db_url)
        with psycopg.connect(conninfo(url.set(database="postgres")), autocommit=True) as conn:
            rows = conn.execute("SELECT pid FROM pg_stat_activity WHERE datname = %s AND pid <> pg_backend_pid()",
                                (url.database,)).fetchall()  # fmt: skip
        return [pid for (pid,) in rows if Path(f"/proc/{pid}").exists()]

    def snapshot(self) -> dict[str, Any]:
        """Returns the counters now."""
        times = os.times()
        return {"t": time.monotonic(), "server": cpu_of(server_pids(self.master)), "pg": cpu_of(self._pg_pids()),
                "bench": times.user + times.system, "machine": machine_busy()}  # fmt: skip

    @staticmethod
    def between(a: dict[str, Any], b: dict[str, Any]) -> dict[str, Any]:
        """Returns the CPU used between two snapshots: seconds and % of one core (server, PostgreSQL backends of
        this database, this benchmark process) and the machine's busy share of all its cores."""
        wall = b["t"] - a["t"]

        def delta(key: str) -> float:
            return sum(v - a[key].get(pid, 0.0) for pid, v in b[key].items())

        server, pg, bench = delta("server"), delta("pg"), b["bench"] - a["bench"]
        busy = (b["machine"][0] - a["machine"][0]) / max(1, b["machine"][1] - a["machine"][1])
        return {"seconds": wall, "server_cpu_s": server, "server_pct": 100 * server / wall, "pg_cpu_s": pg,
                "pg_pct": 100 * pg / wall, "bench_pct": 100 * bench / wall, "machine_busy_pct": 100 * busy}  # fmt: skip


# ------------------------------------------------------------------------------------------------ agents


class PostLog(httpx.HTTPTransport):
    """The Publisher's HTTP transport, recording each POST: (sent_at of its body, status or None, start, end)."""

    def __init__(self, keep: bool = True) -> None:
        super().__init__()
        self.keep = keep
        self.posts: list[tuple[float | None, int | None, float, float]] = []
        self.ok = self.failed = 0

    def handle_request(self, request: httpx.Request) -> httpx.Response:
        sent_at = json.loads(request.content).get("sent_at") if self.keep else None
        start = time.time()
        status = None
        try:
            response = super().handle_request(request)
            status = response.status_code
            return response
        finally:
            if status is not None and status < 300:
                self.ok += 1
            else:
                self.failed += 1
            if self.keep:
                self.posts.append((sent_at, status, start, time.time()))


def progress(set_id: str, session_id: str, k: int, rate: float, taken_at: float) -> dict[str, Any]:
    """Returns progress message k of a set, shaped as kinect_agent.live.set_recorder writes them."""
    return {"set_id": set_id, "exercise_slug": EXERCISE, "state": "recording", "target": 10_000, "count": k % 10_000,
            "elapsed_s": round(k / rate, 2), "session_id": session_id, "sent_at": taken_at,
            "angle_name": "elbow_flexion_left", "angle_deg": 40.0 + 2.5 * (k % 20), "hint": None}  # fmt: skip


def hold_commands(base: str, token: str, stop: threading.Event) -> CommandStream:
    """Starts a thread holding the device's command stream as the agent does; returns the CommandStream."""
    from kinect_agent.live.channel import CommandStream

    stream = CommandStream(base, token, log=lambda _: None)

    def run() -> None:
        for _ in stream.commands(stop):
            pass

    threading.Thread(target=run, name="commands", daemon=True).start()
    return stream


def latency_agent(
    base: str, token: str, set_id: str, n: int, rate: float, connected: Event, go: Event, out: Queue[dict[str, Any]]
) -> None:
    """The home agent of the measured patient, in a process of its own: holds the command stream, sets `connected`,
    waits for `go`, sends n progress messages at rate Hz through the Publisher and puts its records on `out`."""
    from kinect_agent.live.channel import Publisher

    stop = threading.Event()
    stream = hold_commands(base, token, stop)
    if not stream.connected.wait(30):
        out.put({"error": "the command stream did not connect within 30 s"})
        return
    connected.set()
    go.wait(120)
    log = PostLog()
    problems: list[str] = []
    pub = Publisher(base, token, log=problems.append, transport=log)
    session_id = str(uuid.uuid4())
    frames = []
    t0 = time.monotonic()
    for k in range(n):
        time.sleep(max(0.0, t0 + k / rate - time.monotonic()))
        taken_at = time.time()  # the frame arrives
        pub.offer(progress(set_id, session_id, k, rate, taken_at))
        frames.append(taken_at)
    pub.close(timeout=10)
    stop.set()
    stream.close()
    out.put({"frames": frames, "posts": log.posts, "sent": pub.sent, "dropped": pub.dropped, "problems": problems})


@dataclass
class LoadAgent:
    """One home agent of the load: holds its command stream and posts progress at AGENT_HZ until stopped."""

    base: str
    token: str
    set_id: str  # the set the server started on the device (seed)
    stop: threading.Event = field(default_factory=threading.Event)
    log: PostLog = field(default_factory=lambda: PostLog(keep=False))
    offered: int = 0
    coalesced: int = 0

    def start(self) -> None:
        self._stream = hold_commands(self.base, self.token, self.stop)
        self._thread = threading.Thread(target=self._run, name="load-agent", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        from kinect_agent.live.channel import Publisher

        pub = Publisher(self.base, self.token, log=lambda _: None, transport=self.log)
        session_id, t0, k = str(uuid.uuid4()), time.monotonic(), 0
        while not self.stop.wait(max(0.0, t0 + k / AGENT_HZ - time.monotonic())):
            pub.offer(progress(self.set_id, session_id, k, AGENT_HZ, time.time()))
            k += 1
        pub.close(timeout=5)
        self.offered = k
        self.coalesced = pub.dropped - self.log.failed

    def finish(self) -> None:
        self.stop.set()
        self._thread.join(timeout=10)
        self._stream.close()


# ------------------------------------------------------------------------------------------------ light pages


class Pages:
    """Light patient pages: one cookie login and one event stream each (GET /api/v1/events?patient_id&live=true),
    reconnecting after the stream's retry delay when the server ends it, as EventSource does."""

    def __init__(self, base: str, patients: list[dict[str, Any]]) -> None:
        self.base, self.patients = base, patients
        self.connected = self.reconnects = self.errors = 0
        self.progress_events = self.other_events = 0
        self._clients: list[httpx.AsyncClient] = []
        self._tasks: list[asyncio.Task[None]] = []
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_forever, name="pages", daemon=True)
        self._thread.start()

    def _call(self, coro: Coroutine[object, object, Result], timeout: float) -> Result:
        return asyncio.run_coroutine_threadsafe(coro, self._loop).result(timeout)

    def login(self) -> float:
        """Logs every page in (POST /api/v1/auth/login, LOGIN_CONCURRENCY at a time); returns the seconds taken."""
        return self._call(self._login(), timeout=600)

    def open(self, timeout: float = 120.0) -> int:
        """Opens every stream; returns how many are connected (all, unless timeout passed)."""
        return self._call(self._open(timeout), timeout=timeout + 10)

    def close(self) -> None:
        """Closes the streams and the clients, and stops the thread."""
        self._call(self._close(), timeout=30)
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(timeout=10)

    async def _login(self) -> float:
        start = time.monotonic()
        gate = asyncio.Semaphore(LOGIN_CONCURRENCY)

        async def one(patient: dict[str, Any]) -> httpx.AsyncClient:
            client = httpx.AsyncClient(base_url=self.base, timeout=httpx.Timeout(30.0, read=None))
            async with gate:
                r = await client.post("/api/v1/auth/login", json={"email": patient["email"], "password": PASSWORD})
            r.raise_for_status()
            return client

        self._clients = list(await asyncio.gather(*(one(p) for p in self.patients)))
        return time.monotonic() - start

    async def _open(self, timeout: float) -> int:
        pairs = zip(self._clients, self.patients, strict=True)
        self._tasks = [asyncio.create_task(self._stream(client, patient)) for client, patient in pairs]
        deadline = time.monotonic() + timeout
        while self.connected < len(self.patients) and time.monotonic() < deadline:
            await asyncio.sleep(0.1)
        return self.connected

    async def _stream(self, client: httpx.AsyncClient, patient: dict[str, Any]) -> None:
        params = {"patient_id": patient["id"], "live": "true"}
        retry_s, first = 3.0, True
        while True:
            try:
                async with client.stream("GET", "/api/v1/events", params=params) as r:
                    if r.status_code != 200:
                        self.errors += 1
                    else:
                        self.connected += 1
                        self.reconnects += not first
                        first = False
                        try:
                            async for line in r.aiter_lines():
                                if line.startswith("retry:"):
                                    retry_s = int(line[6:]) / 1000
                                elif line.startswith("event:"):
                                    if line[6:].strip() == "live.progress":
                                        self.progress_events += 1
                                    else:
                                        self.other_events += 1
                        finally:
                            self.connected -= 1
            except httpx.HTTPError:
                self.errors += 1
            await asyncio.sleep(retry_s)

    async def _close(self) -> None:
        for task in self._tasks:
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)
        await asyncio.gather(*(c.aclose() for c in self._clients), return_exceptions=True)


# ------------------------------------------------------------------------------------------------ browser


def open_patient_page(browser: Browser, base: str, patient: dict[str, Any]) -> Page:
    """Signs in as the patient through the login form at /; returns their page once its event stream is open."""
    context = browser.new_context(viewport={"width": 1280, "height": 900})
    context.add_init_script(EVENTSOURCE_PROBE)
    page = context.new_page()
    page.goto(f"{base}/")
    page.fill("#email", patient["email"])
    page.fill("#password", PASSWORD)
    page.click("#login-submit")
    page.wait_for_url(f"{base}/patient")
    wait_stream_open(page)
    return page


def wait_stream_open(page: Page) -> None:
    """Waits until the page's event stream is open and the page has asked for the agent's state."""
    page.wait_for_function("() => window.__es && window.__es.opens.length > 0", timeout=30_000)
    page.wait_for_function("() => ['online', 'offline', 'unpaired'].includes(document.getElementById('agent-status')"
                           ".dataset.state)", timeout=30_000)  # fmt: skip


def latency_run(page: Page, base: str, patient: dict[str, Any], n: int, rate: float, usage: Usage) -> dict[str, Any]:
    """Measures frame-to-screen latency of n messages from the patient's agent to their open page."""
    ctx = mp.get_context("spawn")
    connected, go, out = ctx.Event(), ctx.Event(), ctx.Queue()
    args = (base, patient["device"], patient["set_id"], n, rate, connected, go, out)
    agent = ctx.Process(target=latency_agent, args=args)
    agent.start()
    try:
        if not connected.wait(60):
            raise SystemExit("the latency agent's command stream did not connect")
        page.wait_for_function("() => document.getElementById('agent-status').dataset.state === 'online'",
                               timeout=30_000)  # fmt: skip
        page.evaluate(SHOWN_LISTENER)
        opens_before = page.evaluate("() => window.__es.opens.length")
        before = usage.snapshot()
        go.set()
        record = out.get(timeout=n / rate + 120)
        time.sleep(TAIL_S)
        cpu = Usage.between(before, usage.snapshot())
        shown = page.evaluate("() => window.__shown")
        es = page.evaluate("() => window.__es")
    finally:
        agent.join(timeout=30)
        if agent.is_alive():
            agent.kill()
    if "error" in record:
        raise SystemExit(record["error"])
    return account(record, shown, es, opens_before) | {"cpu": cpu}


def account(
    record: dict[str, Any], shown: list[tuple[float, float, float | None]], es: dict[str, Any], opens_before: int
) -> dict[str, Any]:
    """Returns the fate of every message of a run and the latency statistics of those shown (ms)."""
    frames, posts = record["frames"], record["posts"]
    posted = {p[0]: p for p in posts}
    ok = {s for s, status, _, _ in posts if status is not None and status < 300}
    seen: dict[float, tuple[float, float | None]] = {}
    duplicates = 0
    for sent_at, at_ms, frame_ms in shown:
        if sent_at in seen:
            duplicates += 1
            continue
        seen[sent_at] = (at_ms - 1000 * sent_at, None if frame_ms is None else frame_ms - 1000 * sent_at)
    # the page's stream was down from an error until the next open (the browser waits the retry delay)
    opens = es["opens"][opens_before:]
    gaps = [(err, min((o for o in opens if o >= err), default=float("inf"))) for err in es["errors"]]
    fate = {"coalesced": 0, "failed": 0, "reconnecting": 0, "lost": 0, "shown": 0}
    for sent_at in frames:
        if sent_at in seen:
            fate["shown"] += 1
        elif sent_at not in posted:
            fate["coalesced"] += 1
        elif sent_at not in ok:
            fate["failed"] += 1
        elif any(a - 100 <= posted[sent_at][3] * 1000 <= b + 100 for a, b in gaps):
            fate["reconnecting"] += 1
        else:
            fate["lost"] += 1
    lat = [v[0] for v in seen.values()]
    nxt = [v[1] for v in seen.values() if v[1] is not None]
    post_ms = [1000 * (end - start) for _, _, start, end in posts]
    return {
        "offered": len(frames),
        "posted": len(posts),
        **fate,
        "duplicates": duplicates,
        "dropped": len(frames) - fate["shown"],
        "reconnects": len(opens),
        "p50_ms": percentile(lat, 50),
        "p95_ms": percentile(lat, 95),
        "p99_ms": percentile(lat, 99),
        "max_ms": max(lat, default=float("nan")),
        "mean_ms": statistics.fmean(lat) if lat else float("nan"),
        "next_frame_p50_ms": percentile(nxt, 50),
        "next_frame_p95_ms": percentile(nxt, 95),
        "post_p50_ms": percentile(post_ms, 50),
        "post_p95_ms": percentile(post_ms, 95),
        "publisher_problems": record["problems"][:5],
    }


# ------------------------------------------------------------------------------------------------ main


def database(arg: str) -> tuple[str, bool]:
    """Returns (database URL, whether it is a fresh temporary SQLite file) of --db."""
    if arg == "sqlite":
        return f"sqlite:///{tempfile.mkdtemp(prefix='bench-live-')}/live.db", True
    url = make_url(arg)
    if url.get_backend_name() != "postgresql":
        raise SystemExit("--db must be a PostgreSQL URL or the word sqlite")
    if "bench" not in (url.database or ""):
        raise SystemExit(f"--db {url.database!r}: the database is dropped and recreated; its name must contain 'bench'")
    return arg, False


def run(args: argparse.Namespace) -> dict[str, Any]:
    """Runs the whole benchmark; returns the results."""
    from playwright.sync_api import sync_playwright

    from backend.config import Settings

    url, is_sqlite = database(args.db)
    workers = 1 if is_sqlite else args.workers
    inherited = sorted(k for k in os.environ if k.startswith("COACH_"))
    if inherited:
        print(f"note: the server inherits {', '.join(inherited)} from this environment", flush=True)
    stream_max_s = Settings().EVENTS_STREAM_MAX_S  # what the server reads from the same environment
    t0 = time.monotonic()
    if not is_sqlite:
        recreate_database(url)
    migrate(url)
    patients = seed(url, args.pages + 1)  # patient 0: the browser; 1..pages: the light pages; 1..agents: agents
    port = free_port()
    base = f"http://127.0.0.1:{port}"
    server = start_server(url, port, workers)
    usage = Usage(server.pid, url)
    r: dict[str, Any] = {"database": "sqlite" if is_sqlite else "postgresql", "workers": workers,
               "events_stream_max_s": stream_max_s, "inherited_env": inherited,
               "loadavg_before": os.getloadavg()}  # fmt: skip
    pages = Pages(base, patients[1 : args.pages + 1])
    agents: list[LoadAgent] = []
    try:
        r["rss_mb_start"] = rss_mb(server_pids(server.pid))
        r["login_s"] = pages.login()
        r["rss_mb_logins"] = rss_mb(server_pids(server.pid))
        r["setup_s"] = time.monotonic() - t0
        print(f"set up in {r['setup_s']:.0f} s ({args.pages} cookie logins {r['login_s']:.1f} s)", flush=True)
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, headless=True, args=["--no-sandbox"])
            page = open_patient_page(browser, base, patients[0])
            print(f"latency, quiet: {args.messages} messages at {args.rate:g} Hz ...", flush=True)
            r["quiet"] = latency_run(page, base, patients[0], args.messages, args.rate, usage)
            r["rss_mb_before_pages"] = rss_mb(server_pids(server.pid))
            r["pages_connected"] = pages.open()
            time.sleep(SETTLE_S)
            r["rss_mb_pages"] = rss_mb(server_pids(server.pid))
            print(f"{r['pages_connected']} of {args.pages} pages connected; idle window {args.window:g} s ...",
                  flush=True)  # fmt: skip
            a = usage.snapshot()
            time.sleep(args.window)
            r["idle"] = Usage.between(a, usage.snapshot())
            agents = [LoadAgent(base, p["device"], p["set_id"]) for p in patients[1 : args.agents + 1]]
            for agent in agents:
                agent.start()
            time.sleep(SETTLE_S)
            print(f"{args.agents} agents posting at {AGENT_HZ:g} Hz; window {args.window:g} s ...", flush=True)
            a = usage.snapshot()
            events_a = pages.progress_events
            time.sleep(args.window)
            r["agents"] = Usage.between(a, usage.snapshot())
            r["agents"]["page_events_per_s"] = (pages.progress_events - events_a) / r["agents"]["seconds"]
            r["rss_mb_agents"] = rss_mb(server_pids(server.pid))
            page.reload()  # a fresh stream: a whole run fits in its lifetime (reconnects are still counted)
            wait_stream_open(page)
            print(f"latency, loaded: {args.messages} messages at {args.rate:g} Hz ...", flush=True)
            r["loaded"] = latency_run(page, base, patients[0], args.messages, args.rate, usage)
            r["rss_mb_loaded"] = rss_mb(server_pids(server.pid))
            r["pages_connected_end"] = pages.connected
            for agent in agents:
                agent.finish()
            time.sleep(0.5)
            r["load_agents"] = {
                "offered": sum(x.offered for x in agents),
                "posted_ok": sum(x.log.ok for x in agents),
                "failed": sum(x.log.failed for x in agents),
                "coalesced": sum(x.coalesced for x in agents),
                "page_progress_events": pages.progress_events,
            }
            r["pages_reconnects"], r["pages_errors"] = pages.reconnects, pages.errors
            browser.close()
    finally:
        for agent in agents:
            agent.stop.set()
        pages.close()
        stop_server(server)
    r["loadavg_after"] = os.getloadavg()
    r["seconds"] = time.monotonic() - t0
    return r


def report(r: dict[str, Any], args: argparse.Namespace) -> None:
    """Prints the results as tables."""
    n_pages = r["pages_connected"]
    print(f"\nlive loop on {r['database']}, {r['workers']} uvicorn worker(s), loopback, {os.cpu_count()} CPUs; "
          f"load average {r['loadavg_before'][0]:.2f} before, {r['loadavg_after'][0]:.2f} after; "
          f"{r['seconds']:.0f} s in all")  # fmt: skip
    print(f"\nframe -> patient's screen: {args.messages} messages at {args.rate:g} Hz per run, one Chromium page")
    head = (f"{'run':<34}{'offered':>8}{'shown':>7}{'dropped':>8}  {'coal/fail/reconn/lost':<22}"
            f"{'p50':>7}{'p95':>7}{'p99':>7}{'max':>7}  {'frame p95':>9}  {'POST p50/p95':>12}")  # fmt: skip
    print(head + "\n" + "-" * len(head))
    labels = (("quiet", "quiet (this page only)"),
              ("loaded", f"+{n_pages} pages, {args.agents} agents x {AGENT_HZ:g} Hz"))  # fmt: skip
    for key, label in labels:
        x = r[key]
        why = f"{x['coalesced']}/{x['failed']}/{x['reconnecting']}/{x['lost']}"
        print(f"{label:<34}{x['offered']:>8}{x['shown']:>7}{x['dropped']:>8}  {why:<22}{x['p50_ms']:>7.1f}"
              f"{x['p95_ms']:>7.1f}{x['p99_ms']:>7.1f}{x['max_ms']:>7.1f}  {x['next_frame_p95_ms']:>9.1f}  "
              f"{x['post_p50_ms']:>5.1f}/{x['post_p95_ms']:<6.1f}")  # fmt: skip
    print("(ms; dropped = coalesced by the Publisher / failed POST / lost while the page reconnected / lost otherwise;"
          "\n frame p95: to the next frame after drawing; POST: the agent's request round trip)")  # fmt: skip
    print(f"\nserver (master + {r['workers']} worker(s)); {n_pages} light pages = httpx event streams with cookie "
          f"logins, not browsers")  # fmt: skip
    print(f"{'RSS MB':<58}{r['rss_mb_start']:>8.0f}  at start")
    print(f"{'':<58}{r['rss_mb_logins']:>8.0f}  after {args.pages} cookie logins")
    print(f"{'':<58}{r['rss_mb_before_pages']:>8.0f}  before the pages connect (after the quiet run)")
    per_page = 1024 * (r["rss_mb_pages"] - r["rss_mb_before_pages"]) / max(1, n_pages)
    print(f"{'':<58}{r['rss_mb_pages']:>8.0f}  with {n_pages} pages connected ({per_page:+.0f} KB per page)")
    print(f"{'':<58}{r['rss_mb_agents']:>8.0f}  with the agents posting")
    print(f"{'':<58}{r['rss_mb_loaded']:>8.0f}  after the loaded latency run")
    print(f"\n{'CPU, % of one core (CPU s)':<40}{'server':>14}{'PostgreSQL':>14}{'bench':>8}{'machine busy':>14}")
    windows = (("idle", f"idle, {n_pages} pages, {args.window:g} s"),
               ("agents", f"{args.agents} agents x {AGENT_HZ:g} Hz, {args.window:g} s"),
               ("quiet", "quiet latency run"), ("loaded", "loaded latency run"))  # fmt: skip
    for key, label in windows:
        c = r[key]["cpu"] if "cpu" in r[key] else r[key]
        print(f"{label:<40}{c['server_pct']:>7.1f} ({c['server_cpu_s']:>4.1f}){c['pg_pct']:>7.1f} "
              f"({c['pg_cpu_s']:>4.1f}){c['bench_pct']:>8.1f}{c['machine_busy_pct']:>13.1f}%")  # fmt: skip
    la = r["load_agents"]
    print(f"\nload agents: {la['posted_ok']} progress messages posted, {la['failed']} failed, {la['coalesced']} "
          f"coalesced; the light pages received {la['page_progress_events']} live.progress events "
          f"({r['agents']['page_events_per_s']:.1f}/s in the agents' window); reconnects: browser "
          f"{r['quiet']['reconnects']}+{r['loaded']['reconnects']}, pages {r['pages_reconnects']}; page stream "
          f"errors {r['pages_errors']}; streams live {r['events_stream_max_s']:g} s")  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--db", default=DEFAULT_DB,
                        help=f"PostgreSQL URL of a database to RECREATE, or sqlite (default {DEFAULT_DB})")  # fmt: skip
    parser.add_argument("--workers", type=int, default=2, help="uvicorn workers (PostgreSQL; SQLite: 1)")
    parser.add_argument("--messages", type=int, default=1000, help="progress messages per latency run")
    parser.add_argument("--rate", type=float, default=10.0, help="progress messages per second of the measured agent")
    parser.add_argument("--pages", type=int, default=200, help="light patient pages (event streams) of the load")
    parser.add_argument("--agents", type=int, default=20, help=f"agents of the load, each posting at {AGENT_HZ:g} Hz")
    parser.add_argument("--window", type=float, default=15.0, help="CPU measuring window, s")
    parser.add_argument("--target-ms", type=float, default=250.0, help="p95 target of both latency runs")
    parser.add_argument("--quick", action="store_true", help="100 messages, 20 pages, 5 agents, 5 s windows")
    parser.add_argument("--json", type=Path, help="also write the results to this JSON file")
    args = parser.parse_args(argv)
    if args.quick:
        args.messages, args.pages, args.agents, args.window = 100, 20, 5, 5.0
    if args.agents > args.pages:
        parser.error("--agents must not exceed --pages (each agent posts to a patient whose page is connected)")
    r = run(args)
    report(r, args)
    passed = all(r[k]["p95_ms"] <= args.target_ms and r[k]["shown"] > 0 for k in ("quiet", "loaded"))
    r |= {"date": dt.datetime.now(dt.UTC).isoformat(timespec="seconds"), "cpus": os.cpu_count(), "pass": passed,
          "config": {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()}}  # fmt: skip
    print(f"\np95 {r['quiet']['p95_ms']:.1f} ms quiet, {r['loaded']['p95_ms']:.1f} ms loaded, target "
          f"{args.target_ms:g} ms: {'PASS' if passed else 'FAIL'}")  # fmt: skip
    if args.json:
        args.json.write_text(json.dumps(r, indent=2))
    return 0 if passed else 1


if __name__ == "__main__":
    sys.exit(main())
