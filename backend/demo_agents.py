"""Simulated home agents for the demo: one per demo patient, talking to the server only through its HTTP API.

Each agent has its own home folder (config.json with the device token, mode 0600, and its disk queue) under
--home. On start an agent reuses its token when the server still accepts it; otherwise the patient logs in,
creates a pairing code and the agent pairs with it (through `kinect_agent.home.HomeAgent`, the agent's public
entry). Then the agents upload a few weeks of backdated sessions (patient after patient, oldest first, so the
first progress plots fill up early), and after that one new session every --min-interval..--max-interval seconds,
patient after patient. Every session goes capture (simulator) -> filter -> disk queue -> upload, as on a real
home computer.

Run by `coach-server demo` as a child process: `python -m backend.demo_agents --server URL --home DIR`.
It exits when its parent process ends, on SIGTERM, or after --max-sessions live sessions.
"""

from __future__ import annotations

import argparse
import datetime as dt
import hashlib
import json
import os
import random
import signal
import subprocess
import sys
import threading
import time
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx

from backend.demo import DEMO_PASSWORD, PATIENTS
from kinect_agent.home import AgentConfig, AgentError, ConfigError, HomeAgent

STATE_NAME = "demo_state.json"
SESSIONS_PER_WEEK = 2  # backdated sessions per exercise and week


@dataclass
class Agent:
    """One simulated home: the patient it belongs to, its exercises, its folder and its paired configuration."""

    email: str
    name: str
    exercises: tuple[str, ...]
    index: int
    home: Path
    agent: HomeAgent | None = None
    sessions: int = 0
    retry_at: float = 0.0  # time.monotonic() before which a refused sign-in is not tried again

    @property
    def config(self) -> AgentConfig:
        assert self.agent is not None, "connect() first"
        return self.agent.config

    @property
    def label(self) -> str:
        return self.email.split("@")[0]


def _say(line: str) -> None:
    print(f"[demo agents] {line}", flush=True)


def wait_for_server(server: str, timeout_s: float = 60.0) -> None:
    """Blocks until GET /healthz answers 200; raises AgentError after timeout_s."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        try:
            if httpx.get(f"{server}/healthz", timeout=2).status_code == 200:
                return
        except httpx.TransportError:
            pass
        time.sleep(0.25)
    raise AgentError(f"{server}/healthz did not answer within {timeout_s:.0f} s")


def _token_works(config: AgentConfig, server: str) -> bool:
    """Returns whether the server at this address accepts the agent's device token (it may have moved: the demo
    restarted on another --port)."""
    r = httpx.get(f"{server}/api/v1/devices/me", headers={"Authorization": f"Bearer {config.device_token}"}, timeout=10)
    return r.status_code == 200


class SignInRefused(AgentError):
    """The server refuses the patient's sign-in for now (too many failed sign-ins: HTTP 429); retry_s from its
    Retry-After."""

    def __init__(self, message: str, retry_s: float) -> None:
        super().__init__(message)
        self.retry_s = retry_s


def _pairing_code(server: str, email: str) -> str:
    """Logs in as the patient (cookie + CSRF token) and creates a pairing code, as the patient page does; raises
    SignInRefused while the server throttles the sign-in."""
    with httpx.Client(base_url=server, timeout=30) as client:
        login = client.post("/api/v1/auth/login", json={"email": email, "password": DEMO_PASSWORD})
        if login.status_code == 429:
            try:
                retry = float(login.headers.get("Retry-After", "60"))
            except ValueError:
                retry = 60.0
            raise SignInRefused(login.json().get("detail", "too many failed sign-ins"), max(1.0, retry))
        if login.status_code != 200:
            raise AgentError(f"{email}: login failed (HTTP {login.status_code}: {login.text[:200]})")
        body = login.json()
        r = client.post(
            f"/api/v1/patients/{body['user']['id']}/pairing-codes", headers={"X-CSRF-Token": body["csrf_token"]}
        )
        if r.status_code != 201:
            raise AgentError(f"{email}: pairing code refused (HTTP {r.status_code}: {r.text[:200]})")
        return r.json()["code"]


def connect(agent: Agent, server: str) -> None:
    """Reuses the agent's device token when the server accepts it (saving the server's new address if it moved, so
    the sets kept in its queue, bound to this pairing, are still accepted), else pairs the agent anew."""
    try:
        home = HomeAgent.load(agent.home)
    except ConfigError:
        home = None
    if home is not None and _token_works(home.config, server):
        if home.config.server_url != server:
            home = home.moved(server, agent.home)
    else:
        code = _pairing_code(server, agent.email)
        home = HomeAgent.pair(server, code, name=f"{agent.name.split()[0]}'s home agent (simulated)", home=agent.home)
    agent.agent = home
    home.recover()  # sessions interrupted while filtered (demo stopped): queued as recorded


def ensure_connected(agent: Agent, server: str) -> bool:
    """Connects the agent unless it is connected; a throttled sign-in is said in one line and tried again after the
    server's Retry-After (the other agents go on meanwhile). Returns whether the agent is connected."""
    if agent.agent is not None:
        return True
    if time.monotonic() < agent.retry_at:
        return False
    try:
        connect(agent, server)
    except SignInRefused as exc:
        agent.retry_at = time.monotonic() + exc.retry_s
        _say(f"{agent.label}: the server refuses this patient's sign-in for now ({exc}); this home agent pairs in "
             f"{exc.retry_s:.0f} s, the other agents go on")  # fmt: skip
        return False
    return True


def record_one(
    agent: Agent,
    exercise: str,
    *,
    when: dt.datetime,
    seed: int,
    reps: int,
    session_id: str | None = None,
    progress: str = "",
) -> None:
    """Simulates one session of `exercise` started at `when`, queues it durably and drains the agent's queue.

    progress: printed before the outcome line (e.g. "history 5/72: ").
    """
    home = agent.agent
    if home is None:
        raise AgentError(f"{agent.label} is not paired yet")
    started = when.astimezone(dt.UTC).isoformat(timespec="seconds").replace("+00:00", "Z")
    t0 = time.monotonic()
    if session_id is None or home.where(session_id) is None:  # a backfilled session is made once
        session_id = home.record_simulated(exercise, reps=reps, seed=seed, started=started, session_id=session_id)
    t1 = time.monotonic()
    agent.sessions += 1
    report = home.upload()
    took = f"filter {t1 - t0:.1f} s, upload {time.monotonic() - t1:.1f} s"
    for r in report.results:
        outcome = {"sent": f"uploaded (HTTP {r.status_code})", "rejected": f"REJECTED: {r.detail}"}.get(
            r.outcome, f"kept in the queue: {r.detail}"
        )
        what = f"{exercise} started {started}, {reps} reps" if r.session_id == session_id else "queued earlier"
        _say(f"{progress}{agent.label}: {what} ({r.session_id[:8]}) -> {outcome} ({took})")


def backfill_plan(agents: list[Agent], weeks: int, today: dt.date, seed: int) -> list[tuple[dt.datetime, Agent, str]]:
    """Returns [(when, agent, exercise)] of the backdated sessions: patient after patient (the first plots fill up
    first), each oldest first; the same plan on the same day."""
    plan: list[tuple[dt.datetime, Agent, str]] = []
    for agent in agents:
        rng = random.Random(f"{seed}-{agent.email}")
        for exercise in agent.exercises:
            for week in range(weeks, 0, -1):
                days = rng.sample(range(7), SESSIONS_PER_WEEK)
                for day in sorted(days, reverse=True):
                    date = today - dt.timedelta(days=7 * (week - 1) + day + 1)
                    hour, minute = rng.randint(8, 19), rng.randint(0, 59)
                    plan.append((dt.datetime(date.year, date.month, date.day, hour, minute, tzinfo=dt.UTC),
                                 agent, exercise))  # fmt: skip
    return sorted(plan, key=lambda item: (item[1].index, item[0]))


def _state(agent: Agent) -> dict[str, Any]:
    try:
        return json.loads((agent.home / STATE_NAME).read_text())
    except (FileNotFoundError, ValueError):
        return {}


def _save_state(agent: Agent, state: dict[str, Any]) -> None:
    (agent.home / STATE_NAME).write_text(json.dumps(state))


class _Stop:
    """SIGTERM ends the agents at once, even inside a filter or an upload (its default action: the queue's atomic
    writes make any moment safe, and a Python handler would wait for a long numeric call to return); so does the
    end of the parent (checked twice a second by a thread), which ends the agents' whole process group (the live
    agent too: `coach-server demo` starts them in a session of their own)."""

    def __init__(self, parent_pid: int | None) -> None:
        self.parent_pid, self.flag = parent_pid, False
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        if parent_pid is not None:
            threading.Thread(target=self._watch_parent, daemon=True).start()

    def _watch_parent(self) -> None:
        while os.getppid() == self.parent_pid:
            time.sleep(0.5)
        if os.getpgid(0) == os.getpid():  # the leader of its own group (started by the demo): the live agent too
            os.killpg(os.getpid(), signal.SIGTERM)
        os.kill(os.getpid(), signal.SIGTERM)

    def __bool__(self) -> bool:
        return self.flag or (self.parent_pid is not None and os.getppid() != self.parent_pid)

    def sleep(self, seconds: float) -> None:
        end = time.monotonic() + seconds
        while not self and time.monotonic() < end:
            time.sleep(min(0.5, max(end - time.monotonic(), 0.0)))


def start_live_agent(patient: Agent, server: str) -> subprocess.Popen[bytes]:
    """Pairs a second home agent of the patient (its own folder and queue) and runs it as `kinect-agent serve` with
    the simulator as its camera, so the demo's patient page can start a set live."""
    live = Agent(email=patient.email, name=patient.name, exercises=patient.exercises, index=patient.index,
                 home=patient.home.with_name(f"{patient.home.name}-live"))  # fmt: skip
    connect(live, server)
    command = [sys.executable, "-m", "kinect_agent.cli", "serve", "--source", "simulator", "--home", str(live.home)]
    log = open(live.home / "serve.log", "a")  # noqa: SIM115 - the child holds it for its lifetime
    proc = subprocess.Popen(command, stdout=log, stderr=subprocess.STDOUT)
    _say(f"{patient.label}'s home computer waits for Start on the patient page (live sets; log {live.home}/serve.log)")
    return proc


def run_agents(args: argparse.Namespace) -> int:
    """Pairs the agents, uploads the backdated history, then a new session every 30-60 s until stopped."""
    stop = _Stop(args.parent_pid)
    wait_for_server(args.server)
    agents = [Agent(email=e, name=n, exercises=ex, index=i, home=args.home / e.split("@")[0])
              for i, (e, n, ex) in enumerate(PATIENTS)]  # fmt: skip
    ready = sum(ensure_connected(agent, args.server) for agent in agents)
    _say(f"{ready} of {len(agents)} home agents ready (paired, or their device tokens still valid); queues in "
         f"{args.home}")  # fmt: skip
    live = start_live_agent(agents[0], args.server) if args.live and agents[0].agent is not None else None
    try:
        return _upload_sessions(args, agents, stop)
    finally:
        if live is not None:
            live.terminate()
            live.wait(timeout=60)


def _upload_sessions(args: argparse.Namespace, agents: list[Agent], stop: _Stop) -> int:
    """Uploads the backdated history, then a new session every min..max interval seconds until stopped."""
    rng = random.Random(args.seed)
    todo = [a for a in agents if a.agent is not None and not _state(a).get("backfilled")]
    plan = backfill_plan(todo, args.history_weeks, dt.date.today(), args.seed)
    started = time.monotonic()
    if plan:
        _say(f"uploading {len(plan)} backdated sessions ({args.history_weeks} weeks of history); "
             "\"history ready\" follows when all are in")  # fmt: skip
    for done, (when, agent, exercise) in enumerate(plan, start=1):
        if stop:
            return 0
        # Deterministic id, seed and reps: after an interruption the same session is rebuilt byte for byte and the
        # server answers 200 (already stored) instead of storing it twice.
        key = f"{args.seed}/{agent.email}/{exercise}/{when.isoformat()}"
        seed = int.from_bytes(hashlib.sha256(key.encode()).digest()[:4], "little")
        session_id = str(uuid.uuid5(uuid.NAMESPACE_URL, key))
        progress = f"history {done}/{len(plan)}: "
        record_one(agent, exercise, when=when, seed=seed, reps=6 + seed % 5, session_id=session_id, progress=progress)
    for agent in todo:
        _save_state(agent, {**_state(agent), "backfilled": True})
    if plan:
        _say(f"history ready: {len(plan)} backdated sessions uploaded in {time.monotonic() - started:.0f} s; the "
             "charts and the dashboard are complete")  # fmt: skip
    else:
        _say("history ready (uploaded in an earlier run)" if args.history_weeks else "history ready (none asked for)")
    live = turn = 0
    while not stop and (args.max_sessions is None or live < args.max_sessions):
        agent = agents[turn % len(agents)]
        turn += 1
        if not ensure_connected(agent, args.server):  # its turn passes to the next agent
            if not any(a.agent is not None for a in agents):
                stop.sleep(1.0)
            continue
        exercise = agent.exercises[(live // len(agents)) % len(agent.exercises)]
        record_one(agent, exercise, when=dt.datetime.now(dt.UTC), seed=10**6 + live, reps=rng.randint(6, 10))
        live += 1
        stop.sleep(rng.uniform(args.min_interval, args.max_interval))
    return 0


def build_parser() -> argparse.ArgumentParser:
    """Returns the parser of `python -m backend.demo_agents`."""
    p = argparse.ArgumentParser(prog="python -m backend.demo_agents", description=__doc__.split("\n\n")[0])
    p.add_argument("--server", required=True, help="server URL, e.g. http://127.0.0.1:8000")
    p.add_argument("--home", type=Path, required=True, help="folder of the agents' homes (config + queue each)")
    p.add_argument("--history-weeks", type=int, default=3, help="weeks of backdated sessions (default 3)")
    p.add_argument("--min-interval", type=float, default=30.0, help="seconds between live sessions, at least")
    p.add_argument("--max-interval", type=float, default=60.0, help="seconds between live sessions, at most")
    p.add_argument("--max-sessions", type=int, help="stop after this many live sessions (default: never)")
    p.add_argument("--parent-pid", type=int, help="exit when this process is no longer the parent")
    p.add_argument("--seed", type=int, default=2026)
    p.add_argument("--no-live", dest="live", action="store_false",
                   help="do not run the first patient's live home agent (kinect-agent serve)")  # fmt: skip
    return p


def main(argv: list[str] | None = None) -> int:
    """Runs the simulated agents; errors print one line and exit 2."""
    args = build_parser().parse_args(argv)
    if args.history_weeks < 0 or not 0 < args.min_interval <= args.max_interval:
        print("demo agents: --history-weeks must be >= 0 and 0 < --min-interval <= --max-interval", file=sys.stderr)
        return 2
    try:
        return run_agents(args)
    except (AgentError, ValueError, httpx.HTTPError) as exc:
        print(f"[demo agents] error: {exc}", file=sys.stderr, flush=True)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
