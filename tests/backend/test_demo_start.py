"""Starting and stopping the demo as a new user does (issue 23, point 9): a busy port is one line naming --port,
Ctrl-C ends everything within 2 s without a traceback, a throttled sign-in does not end the other simulated agents,
and a set kept on an agent's disk is uploaded after the demo restarts on another port."""

from __future__ import annotations

import os
import re
import signal
import socket
import subprocess
import sys
import time
from contextlib import contextmanager
from pathlib import Path

import httpx
import pytest

from backend.demo import DEMO_PASSWORD
from kinect_agent.home import HomeAgent
from tests.backend.test_demo import _demo_processes

pytestmark = pytest.mark.own_database  # the demo runs on its own SQLite file


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _demo(tmp_path: Path, port: int, *extra: str, log: str = "demo.log") -> subprocess.Popen[str]:
    """Starts `coach-server demo` in a process group of its own (as a terminal runs it), output to tmp_path/log."""
    out = open(tmp_path / log, "w")  # noqa: SIM115 - the child holds it
    return subprocess.Popen(
        [sys.executable, "-m", "backend.cli", "demo", "--port", str(port), "--db", str(tmp_path / "demo.db"), *extra],
        stdout=out, stderr=subprocess.STDOUT, text=True, cwd=tmp_path, start_new_session=True,
    )  # fmt: skip


def _wait_healthy(base: str, proc: subprocess.Popen[str], log: Path) -> None:
    for _ in range(240):
        try:
            if httpx.get(f"{base}/healthz", timeout=1).status_code == 200:
                return
        except httpx.TransportError:
            pass
        if proc.poll() is not None:
            pytest.fail(f"demo exited early:\n{log.read_text()}")
        time.sleep(0.25)
    pytest.fail(f"the demo did not answer /healthz within 60 s:\n{log.read_text()}")


@contextmanager
def _server(tmp_path: Path, port: int, log: str):
    """The demo's server alone (--no-agents) on port; stopped on exit."""
    proc = _demo(tmp_path, port, "--no-agents", log=log)
    base = f"http://127.0.0.1:{port}"
    try:
        _wait_healthy(base, proc, tmp_path / log)
        yield base
    finally:
        os.killpg(proc.pid, signal.SIGINT)
        proc.wait(timeout=30)


def _agents(server: str, home: Path, *extra: str) -> subprocess.CompletedProcess[str]:
    command = [sys.executable, "-m", "backend.demo_agents", "--server", server, "--home", str(home), "--no-live",
               "--history-weeks", "0", "--min-interval", "0.1", "--max-interval", "0.2", *extra]  # fmt: skip
    return subprocess.run(command, capture_output=True, text=True, timeout=600)


def test_a_busy_port_is_one_line_naming_the_port_option(tmp_path):
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        t0 = time.monotonic()
        done = subprocess.run([sys.executable, "-m", "backend.cli", "demo", "--port", str(port), "--db",
                               str(tmp_path / "demo.db")], capture_output=True, text=True, timeout=120)  # fmt: skip
    lines = (done.stdout + done.stderr).strip().splitlines()
    assert done.returncode == 2, lines
    assert len(lines) == 1 and "--port" in lines[0] and "in use" in lines[0] and str(port) in lines[0], lines
    assert time.monotonic() - t0 < 30 and not (tmp_path / "demo.db").exists()  # nothing was started or made


def test_ctrl_c_ends_the_demo_and_its_agents_within_2_s_without_a_traceback(tmp_path):
    port = _free_port()
    proc = _demo(tmp_path, port, "--history-weeks", "0", "--agent-interval", "60", "60")
    log = tmp_path / "demo.log"
    try:
        _wait_healthy(f"http://127.0.0.1:{port}", proc, log)
        deadline = time.monotonic() + 240
        while "home agents ready" not in log.read_text() or "waits for Start" not in log.read_text():
            assert time.monotonic() < deadline, log.read_text()
            time.sleep(0.5)
        time.sleep(2)  # the agents are busy (a first live session, the live agent's camera)
        t0 = time.monotonic()
        os.killpg(proc.pid, signal.SIGINT)  # what a terminal's Ctrl-C does: SIGINT to the foreground group
        proc.wait(timeout=30)
        while _demo_processes(str(tmp_path)) and time.monotonic() - t0 < 30:
            time.sleep(0.05)
        took = time.monotonic() - t0
    finally:
        for pid in _demo_processes(str(tmp_path)):
            os.kill(pid, signal.SIGKILL)
    out = log.read_text()
    assert "Traceback" not in out, out[-3000:]
    assert took < 2.0, f"Ctrl-C took {took:.1f} s to end the demo and its agents"


def test_a_throttled_sign_in_does_not_end_the_other_agents(tmp_path):
    port = _free_port()
    with _server(tmp_path, port, "server.log") as base:
        for _ in range(6):  # rose's sign-in is refused for 15 minutes after 5 failures
            httpx.post(f"{base}/api/v1/auth/login", json={"email": "rose@demo.clinic", "password": "wrong password"})
        refused = httpx.post(f"{base}/api/v1/auth/login", json={"email": "rose@demo.clinic", "password": DEMO_PASSWORD})
        assert refused.status_code == 429
        done = _agents(base, tmp_path / "agents", "--max-sessions", "2")
    out = done.stdout + done.stderr
    assert done.returncode == 0, out
    assert "rose: the server refuses this patient's sign-in for now" in out, out
    assert "5 of 6 home agents ready" in out, out
    assert out.count("uploaded (HTTP 201)") == 2, out


def test_a_set_kept_on_disk_is_uploaded_after_the_demo_restarts_on_another_port(tmp_path):
    home = tmp_path / "agents"
    with _server(tmp_path, _free_port(), "first.log") as base:
        first = _agents(base, home, "--max-sessions", "1")
        assert first.returncode == 0, first.stdout + first.stderr
    rose = HomeAgent.load(home / "rose")
    kept = rose.record_simulated("seated_knee_extension", reps=5, seed=7)  # made while the server was away
    assert rose.where(kept) == "pending"
    with _server(tmp_path, _free_port(), "second.log") as base:  # the old port is taken: --port 8001, say
        again = _agents(base, home, "--max-sessions", "1")
    out = again.stdout + again.stderr
    assert again.returncode == 0, out
    assert f"({kept[:8]}) -> uploaded (HTTP 201)" in out and "REJECTED" not in out, out
    assert HomeAgent.load(home / "rose").where(kept) == "sent"
    assert HomeAgent.load(home / "rose").config.device_token == rose.config.device_token  # not paired anew


def test_history_ready_is_said_once_the_backdated_sessions_are_in_and_a_restart_stores_none_twice(tmp_path):
    home = tmp_path / "agents"
    with _server(tmp_path, _free_port(), "server.log") as base:
        first = _agents(base, home, "--history-weeks", "1", "--max-sessions", "0")
        again = _agents(base, home, "--history-weeks", "1", "--max-sessions", "0")  # the demo started once more
        login = httpx.post(f"{base}/api/v1/auth/login", json={"email": "rose@demo.clinic", "password": DEMO_PASSWORD})
    out = first.stdout + first.stderr
    assert first.returncode == 0, out
    planned = re.search(r"uploading (\d+) backdated sessions \(1 weeks of history\)", out)
    assert planned is not None, out
    n = int(planned.group(1))
    assert n > 0 and out.count("uploaded (HTTP 201)") == n, out
    assert re.search(rf"history ready: {n} backdated sessions uploaded in \d+ s", out), out
    assert out.index("history ready:") > out.rindex("uploaded (HTTP 201)"), out  # said when the last one is in
    out = again.stdout + again.stderr
    assert again.returncode == 0, out
    assert "history ready (uploaded in an earlier run)" in out and "HTTP 201" not in out, out
    assert login.status_code == 200
