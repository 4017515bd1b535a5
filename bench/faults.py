"""Fault bench of the home agent's exactly-once delivery (issue 12): randomised trials against the real server.

    python bench/faults.py [--trials 200] [--seed 1] [--json OUT]

Setup (not measured): a fresh database (an SQLite file in a temp folder), migrated, with one patient; the real
server as a uvicorn subprocess on loopback (bench.dashboard_load.start_server); the agent paired through the real
API (kinect_agent.pairing), its home in the temp folder. The agent runs as real subprocesses of its own code
(capture.queue_session, upload.drain) where a trial kills it; otherwise in this process. A TCP proxy on
loopback (this file) cuts connections.

Each trial records one simulated set (2-3 repetitions) and delivers it through one fault, chosen at random:
    server_down        recorded and queued while the server is down; uploaded once it is back
    server_killed      the server is SIGKILLed at a random moment of an upload pass, restarted, the pass run again
    agent_killed_writing    the agent is SIGKILLed at a random moment while it holds, filters and queues the set;
                       the next start recovers the raw copy and uploads it (a set counts as captured once its raw
                       copy was on disk: the agent says so right after writing it)
    agent_killed_uploading  the agent is SIGKILLed at a random moment of an upload pass; the next pass uploads
    cut_request        the proxy closes the connection after a random part of the request
    lost_response      the proxy lets the server store the set and answer, then closes before the answer arrives
    sent_twice         the same file delivered again from a second queue (a restored backup, a second agent)
    disk_full          writing the filtered set to the queue fails with ENOSPC once or twice: the agent says so, keeps
                       the set in memory and writes it once there is room again (every RETRY_S, 10 s); then uploads
    broken_file        a file truncated on purpose: it must end in rejected/, not stored
Checked by content, after every trial and at the end: each captured set is stored exactly once, with the SHA-256 of
the file the agent sent (its receipt), no session id or content stored twice, and only the broken files set aside.
Prints the counts per kind: captured, stored, lost, duplicated, held or rejected.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import json
import os
import random
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
import uuid
from collections import Counter, defaultdict
from pathlib import Path
from typing import TypedDict

ROOT_DIR = Path(__file__).resolve().parents[1]
if str(ROOT_DIR) not in sys.path:  # `python bench/faults.py` puts bench/ first, not the repository
    sys.path.insert(0, str(ROOT_DIR))

from sqlalchemy import select  # noqa: E402
from sqlalchemy.orm import Session  # noqa: E402

from bench.dashboard_load import start_server  # noqa: E402
from bench.ingest import open_engine  # noqa: E402
from kinect_agent.home import HomeAgent  # noqa: E402

KINDS = ("server_down", "server_killed", "agent_killed_writing", "agent_killed_uploading", "cut_request",
         "lost_response", "sent_twice", "disk_full", "broken_file")  # fmt: skip
EXERCISES = ("squat", "elbow_flexion", "shoulder_abduction", "seated_knee_extension")

# The agent's own code, run as a process of its own so that it can be SIGKILLed at any moment.
AGENT_SCRIPT = r"""
import sys
sys.path.insert(0, sys.argv[1])
from kinect_agent.capture import capture, queue_session
from kinect_agent.commands.upload import upload_queue
from kinect_agent.config import load_config
from kinect_agent.queue import SessionQueue
mode = sys.argv[2]
if mode == "record":
    exercise, reps, seed, session_id = sys.argv[3], int(sys.argv[4]), int(sys.argv[5]), sys.argv[6]
    real_hold = SessionQueue.hold
    def hold(self, payload):
        path = real_hold(self, payload)
        print("held", payload.session_id, flush=True)
        return path
    SessionQueue.hold = hold
    config = load_config()
    queue = SessionQueue(config.queue_dir)
    rec = capture("simulator", exercise=exercise, reps=reps, seed=seed)
    queue_session(queue, rec, session_id=session_id, recorded_by=config.recorded_by)
    print("queued", flush=True)
else:
    report = upload_queue()
    print("drained", report.remaining, flush=True)
"""


class Outcome(TypedDict):
    """Bench.check: counts of captured and stored sets, the session ids lost, duplicated (and content hashes stored
    twice), with a receipt whose hash differs from the stored one, set aside ({id: where}), set aside without being
    broken on purpose, broken on purpose yet stored; how many are still pending."""

    captured: int
    stored: int
    lost: list[str]
    duplicated: list[str]
    receipt_hash_mismatch: list[str]
    set_aside: dict[str, str]
    set_aside_not_broken: list[str]
    broken_stored: list[str]
    pending: int


# ---------------------------------------------------------------------------------------------- proxy


class CuttingProxy:
    """A loopback TCP proxy to the server; arm(mode, cut) makes the next connection fail: "request" closes it after
    `cut` bytes of the request reached the server, "response" after the server's whole answer arrived here."""

    def __init__(self, server_port: int) -> None:
        self.server_port, self.cut = server_port, 0
        self.mode: str | None = None
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.port = self.sock.getsockname()[1]
        threading.Thread(target=self._accept, daemon=True).start()

    def arm(self, mode: str, cut: int = 0) -> None:
        self.mode, self.cut = mode, cut

    def _accept(self) -> None:
        while True:
            client, _ = self.sock.accept()
            mode, self.mode = self.mode, None
            threading.Thread(target=self._serve, args=(client, mode, self.cut), daemon=True).start()

    def _serve(self, client: socket.socket, mode: str | None, cut: int) -> None:
        with client, socket.create_connection(("127.0.0.1", self.server_port)) as server:
            if mode == "request":
                data = b""
                while len(data) < cut and (chunk := client.recv(65536)):
                    data += chunk
                server.sendall(data[:cut])
                return  # both closed mid-request
            up = threading.Thread(target=self._pipe, args=(client, server), daemon=True)
            up.start()
            if mode == "response":
                server.settimeout(30)
                with contextlib.suppress(OSError):
                    while server.recv(65536):  # the server answers; the answer never reaches the agent
                        pass
                return
            self._pipe(server, client)

    @staticmethod
    def _pipe(src: socket.socket, dst: socket.socket) -> None:
        with contextlib.suppress(OSError):
            while chunk := src.recv(65536):
                dst.sendall(chunk)
            dst.shutdown(socket.SHUT_WR)


# ---------------------------------------------------------------------------------------------- bench


class Bench:
    """The server, the agent's home and the bookkeeping of every trial."""

    def __init__(self, db_url: str, folder: Path, seed: int) -> None:
        self.folder, self.rng = folder, random.Random(seed)
        self.engine, self.cleanup = open_engine(db_url)
        self.url = str(self.engine.url.render_as_string(hide_password=False))
        self.port = _free_port()
        self.server = start_server(self.url, self.port, 1)
        self.home = folder / "agent"
        self.env = {**os.environ, "KINECT_AGENT_HOME": str(self.home)}
        os.environ["KINECT_AGENT_HOME"] = str(self.home)
        self.patient_id = self._pair()
        self.captured: dict[str, str] = {}  # session id -> exercise, of every set whose raw copy was on disk
        self.broken: set[str] = set()

    def _pair(self) -> int:
        from backend.devices.service import create_pairing_code
        from backend.users.service import create_user
        from kinect_agent.pairing import pair

        with Session(self.engine) as s, s.begin():
            patient = create_user(db_session=s, email=f"faults-{os.getpid()}@example.org", password=None,
                                  role="patient", full_name="Fault Bench")  # fmt: skip
            _, code = create_pairing_code(db_session=s, patient_id=patient.id, created_by_id=patient.id, minutes=15)
            patient_id = patient.id
        pair(f"http://127.0.0.1:{self.port}", code, name="fault bench", home=self.home)
        return patient_id

    # -- the server ------------------------------------------------------------------------------------------

    def kill_server(self) -> None:
        self.server.send_signal(signal.SIGKILL)
        self.server.wait()

    def start_server(self) -> None:
        if self.server.poll() is not None:
            self.server = start_server(self.url, self.port, 1)

    # -- the agent -------------------------------------------------------------------------------------------

    def agent(self, *args: str) -> subprocess.Popen[str]:
        return subprocess.Popen([sys.executable, "-c", AGENT_SCRIPT, str(ROOT_DIR), *args], env=self.env,
                                stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)  # fmt: skip

    def record(self, kill_after: float | None = None) -> str:
        """Records one set (in an agent process SIGKILLed after kill_after s when given, else in this one); returns
        its session id."""
        session_id, exercise = str(uuid.uuid4()), self.rng.choice(EXERCISES)
        reps, seed = self.rng.randint(2, 3), self.rng.randint(0, 10**6)
        if kill_after is None:
            HomeAgent.load(self.home).record_simulated(exercise, reps=reps, seed=seed, session_id=session_id)
            self.captured[session_id] = exercise
            return session_id
        proc = self.agent("record", exercise, str(reps), str(seed), session_id)
        time.sleep(kill_after)
        proc.send_signal(signal.SIGKILL)
        out, _ = proc.communicate(timeout=120)
        if f"held {session_id}" in out:
            self.captured[session_id] = exercise
        return session_id

    def upload(self, kill_after: float | None = None) -> None:
        """One upload pass in an agent process (SIGKILLed after kill_after s if given)."""
        proc = self.agent("upload")
        if kill_after is not None:
            time.sleep(kill_after)
            proc.send_signal(signal.SIGKILL)
        proc.communicate(timeout=300)

    def drain_here(self, base_url: str | None = None) -> None:
        """One upload pass in this process, optionally through another address (the proxy, whose fault must hit the
        pass's one try)."""
        HomeAgent.load(self.home).upload(attempts=1 if base_url else 3, base_delay_s=0.05, server_url=base_url)

    def settle(self) -> None:
        """Server up, agent restarted (the start-up recovery of a new agent) and the queue drained until nothing is
        pending."""
        self.start_server()
        for _ in range(5):
            agent = HomeAgent.load(self.home)
            agent.recover()
            self.drain_here()
            if not agent.queue.pending() and not list(agent.queue.captured_dir.glob("*.khs")):
                return

    # -- the trials ------------------------------------------------------------------------------------------

    def trial(self, kind: str) -> None:
        rng = self.rng
        if kind == "server_down":
            self.kill_server()
            self.record()
            self.upload()  # refused by a closed port: kept
        elif kind == "server_killed":
            self.record()
            proc = self.agent("upload")
            time.sleep(rng.uniform(0.0, 0.6))
            self.kill_server()
            proc.communicate(timeout=300)
        elif kind == "agent_killed_writing":
            self.record(kill_after=rng.uniform(0.0, 2.5))
        elif kind == "agent_killed_uploading":
            self.record()
            self.upload(kill_after=rng.uniform(0.0, 1.0))
        elif kind in ("cut_request", "lost_response"):
            self.record()
            proxy = CuttingProxy(self.port)
            size = _newest_pending_size()
            proxy.arm("request" if kind == "cut_request" else "response", rng.randint(1, max(1, size)))
            self.drain_here(f"http://127.0.0.1:{proxy.port}")
        elif kind == "sent_twice":
            session_id = self.record()
            data = _pending_bytes(session_id)
            self.settle()
            if data is not None:
                self._send_copy_again(session_id, data)
        elif kind == "disk_full":
            self._record_onto_a_full_disk()
        elif kind == "broken_file":
            self._queue_broken_file()
        self.settle()

    def _send_copy_again(self, session_id: str, data: bytes) -> None:
        """Delivers the stored set's file again from a second queue, as a restored backup would."""
        from kinect_agent.config import load_config
        from kinect_agent.queue import SessionQueue
        from kinect_agent.upload import Uploader, drain

        config = load_config()
        second = SessionQueue(self.folder / "second-queue")
        second.enqueue_bytes(session_id, data)
        with Uploader(config.server_url, config.device_token) as uploader:
            drain(second, uploader)

    def _record_onto_a_full_disk(self) -> None:
        """Records one set in this process whose queue write of the filtered set fails with ENOSPC once or twice
        (the family frees space meanwhile); the agent must say so and queue the set once there is room."""
        import kinect_agent.queue as queue_module
        from kinect_agent.capture import capture, queue_session
        from kinect_agent.config import load_config

        config = load_config()
        queue = queue_module.SessionQueue(config.queue_dir)
        session_id, real = str(uuid.uuid4()), queue_module._write_durably
        calls: list[Path] = []
        refusals, told = self.rng.randint(1, 2), list[str]()

        def full_disk(path: Path, data: bytes) -> None:
            calls.append(path)
            if path.parent == queue.pending_dir and sum(p.parent == queue.pending_dir for p in calls) <= refusals:
                raise OSError(errno.ENOSPC, "No space left on device", str(path))
            real(path, data)

        queue_module._write_durably = full_disk
        try:
            rec = capture("simulator", exercise=self.rng.choice(EXERCISES), reps=2, seed=self.rng.randint(0, 10**6))
            queue_session(queue, rec, session_id=session_id, recorded_by=config.recorded_by, say=told.append)
        finally:
            queue_module._write_durably = real
        if not any("disk of this computer is full" in t for t in told):
            raise RuntimeError(f"disk_full: the agent did not say the disk was full (said {told})")
        if any(p.parent == queue.captured_dir for p in calls):
            self.captured[session_id] = "disk_full"
        for lock in queue._locks.values():  # this "process" is gone: its locks with it
            lock.close()

    def _queue_broken_file(self) -> None:
        from kinect_agent.capture import capture, make_payload
        from kinect_agent.config import load_config
        from kinect_agent.formats.session_file import encode
        from kinect_agent.queue import SessionQueue

        config = load_config()
        session_id = str(uuid.uuid4())
        rec = capture("simulator", exercise="squat", reps=2, seed=self.rng.randint(0, 10**6))
        data = encode(make_payload(rec, session_id=session_id, recorded_by=config.recorded_by))
        SessionQueue(config.queue_dir).enqueue_bytes(session_id, data[: len(data) // 2])
        self.broken.add(session_id)

    # -- the checks ------------------------------------------------------------------------------------------

    def stored(self) -> dict[str, list[str]]:
        """Returns {client session id: [content hash of each stored row]} of the bench's patient."""
        from backend.sessions.models import ExerciseSession

        with Session(self.engine) as s:
            rows = s.execute(select(ExerciseSession.client_session_id, ExerciseSession.content_hash)
                             .where(ExerciseSession.patient_id == self.patient_id)).all()  # fmt: skip
        out: dict[str, list[str]] = defaultdict(list)
        for client_id, content_hash in rows:
            out[str(client_id)].append(content_hash)
        return out

    def check(self) -> Outcome:
        """Returns what became of every captured set: stored, lost, duplicated, set aside or still pending."""
        from kinect_agent.config import load_config
        from kinect_agent.queue import SessionQueue

        queue = SessionQueue(load_config().queue_dir)
        stored = self.stored()
        receipts = {p.stem: json.loads(p.read_text()) for p in queue.sent_dir.glob("*.json")}
        hashes = Counter(h for hs in stored.values() for h in hs)
        lost = [sid for sid in self.captured if sid not in stored]
        duplicated = [sid for sid, hs in stored.items() if len(hs) > 1] + [h for h, n in hashes.items() if n > 1]
        mismatched = [sid for sid, r in receipts.items() if sid in stored and r.get("content_hash") not in stored[sid]]
        aside = {item["session_id"]: item["where"] for item in queue.set_aside()}
        return {
            "captured": len(self.captured),
            "stored": len(stored),
            "lost": lost,
            "duplicated": duplicated,
            "receipt_hash_mismatch": mismatched,
            "set_aside": aside,
            "set_aside_not_broken": [sid for sid in aside if sid not in self.broken],
            "broken_stored": [sid for sid in self.broken if sid in stored],
            "pending": len(queue.pending()),
        }

    def close(self) -> None:
        if self.server.poll() is None:
            self.server.terminate()
            self.server.wait(timeout=30)
        self.engine.dispose()
        self.cleanup()


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _pending_bytes(session_id: str) -> bytes | None:
    from kinect_agent.config import load_config
    from kinect_agent.queue import SessionQueue

    path = SessionQueue(load_config().queue_dir).pending_dir / f"{session_id}.khs"
    return path.read_bytes() if path.exists() else None


def _newest_pending_size() -> int:
    from kinect_agent.config import load_config
    from kinect_agent.queue import SessionQueue

    pending = SessionQueue(load_config().queue_dir).pending()
    return pending[-1].stat().st_size if pending else 1000


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--trials", type=int, default=200)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--json", type=Path)
    parser.add_argument("--kinds", nargs="+", choices=KINDS, default=list(KINDS), help="the faults to draw from")
    args = parser.parse_args(argv)
    folder = Path(tempfile.mkdtemp(prefix="coach-faults-"))
    bench = Bench(f"sqlite:///{folder / 'faults.db'}", folder, args.seed)
    per_kind: Counter[str] = Counter()
    started = time.perf_counter()
    try:
        for k in range(args.trials):
            kind = bench.rng.choice(args.kinds)
            per_kind[kind] += 1
            bench.trial(kind)
            if (k + 1) % 20 == 0:
                report = bench.check()
                print(f"{k + 1} trials: {report['captured']} captured, {report['stored']} stored, "
                      f"{len(report['lost'])} lost, {len(report['duplicated'])} duplicated", flush=True)  # fmt: skip
        report = bench.check()
    finally:
        bench.close()
    seconds = time.perf_counter() - started
    print(f"\nfault bench, {args.trials} trials (seed {args.seed}) in {seconds:.0f} s, server on SQLite")
    print("trials per fault: " + ", ".join(f"{kind} {per_kind[kind]}" for kind in KINDS))
    print(f"captured {report['captured']}, stored {report['stored']}, lost {len(report['lost'])}, duplicated "
          f"{len(report['duplicated'])}, receipts whose hash differs from the stored one "
          f"{len(report['receipt_hash_mismatch'])}")  # fmt: skip
    print(f"set aside {len(report['set_aside'])} (broken on purpose: {len(bench.broken)}; others: "
          f"{len(report['set_aside_not_broken'])}); broken files stored: {len(report['broken_stored'])}; "
          f"still pending: {report['pending']}")  # fmt: skip
    if args.json:
        args.json.write_text(json.dumps({"per_kind": per_kind, "seconds": seconds, **report}, indent=1, default=str))
    shutil.rmtree(folder, ignore_errors=True)
    bad = report["lost"] or report["duplicated"] or report["receipt_hash_mismatch"] or report["set_aside_not_broken"]
    return 1 if bad or report["broken_stored"] or report["pending"] else 0


if __name__ == "__main__":
    sys.exit(main())
