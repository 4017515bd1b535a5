"""The queue's rough corners: a file the server fails on again and again is held aside (with the server's answer)
so that the others go on; a raw copy left by a crash is queued at once when its process is gone, and dropped when
its session is already queued or stored."""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
import textwrap
import uuid
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import pytest

from kinect_agent import skeleton
from kinect_agent.formats.session_file import SessionPayload
from kinect_agent.queue import HOLD_AFTER_SERVER_ERRORS, SessionQueue
from kinect_agent.recording import Metadata, Recording
from kinect_agent.upload import RetryPolicy, Uploader, drain

REPO = Path(__file__).resolve().parents[2]
FAST = RetryPolicy(max_attempts=2, base_delay_s=0.0)


def session_payload(seed: int) -> SessionPayload:
    rng = np.random.default_rng(seed)
    positions = rng.normal(0.0, 0.3, (30, skeleton.J, 3)) + [0.0, 0.0, 2.5]
    rec = Recording.from_positions(np.arange(30) / 30.0, positions, Metadata(device="simulator", exercise="squat"))
    return SessionPayload(session_id=str(uuid.uuid4()), raw=rec)


class Server(httpx.BaseTransport):
    """A server that answers `failing` bodies with `status` and stores every other one (201)."""

    def __init__(self, failing: set[bytes], status: int) -> None:
        self.failing, self.status = failing, status
        self.stored: list[bytes] = []

    def handle_request(self, request: httpx.Request) -> httpx.Response:
        body = request.read()
        if body in self.failing:
            return httpx.Response(self.status, json={"error": "InternalError", "detail": "internal server error"})
        self.stored.append(body)
        return httpx.Response(201, json={"id": len(self.stored), "patient_id": 1, "exercise_slug": "squat"})


def _queue_three(tmp_path: Path) -> tuple[SessionQueue, list[Path]]:
    queue = SessionQueue(tmp_path / "queue")
    return queue, [queue.enqueue(session_payload(seed)) for seed in range(3)]


def _passes(queue: SessionQueue, server: Server, n: int) -> list[Any]:
    reports = []
    for _ in range(n):
        with Uploader("http://coach.test", "khd_x", transport=server, policy=FAST, sleep=lambda s: None) as up:
            reports.append(drain(queue, up))
    return reports


def test_a_file_the_server_fails_on_again_and_again_is_held_and_the_others_go_on(tmp_path) -> None:
    queue, (bad, good1, good2) = _queue_three(tmp_path)
    server = Server({bad.read_bytes()}, 500)
    reports = _passes(queue, server, HOLD_AFTER_SERVER_ERRORS)
    assert len(server.stored) == 2, "the files behind the failing one are not held back"
    assert [r.count("held") for r in reports] == [0] * (HOLD_AFTER_SERVER_ERRORS - 1) + [1]
    held = queue.held_dir / bad.name
    assert held.exists() and not bad.exists() and queue.counts().held == 1 and queue.pending() == []
    (aside,) = queue.set_aside()
    assert aside["where"] == "held" and aside["status_code"] == 500 and "internal server error" in aside["detail"]
    assert queue.requeue_held() == [bad] and queue.pending() == [bad]  # the server was mended: it goes again
    assert not (queue.pending_dir / f"{bad.stem}.failures.json").exists()


@pytest.mark.parametrize("status", [502, 503, 504])
def test_a_server_that_is_down_or_busy_never_makes_a_file_held(tmp_path, status: int) -> None:
    queue, files = _queue_three(tmp_path)
    server = Server({f.read_bytes() for f in files}, status)
    _passes(queue, server, HOLD_AFTER_SERVER_ERRORS + 2)
    assert queue.pending() == files and queue.counts().held == 0


def test_a_different_server_error_starts_the_count_again(tmp_path) -> None:
    queue, (bad, _, _) = _queue_three(tmp_path)
    _passes(queue, Server({bad.read_bytes()}, 500), HOLD_AFTER_SERVER_ERRORS - 1)
    _passes(queue, Server({bad.read_bytes()}, 501), HOLD_AFTER_SERVER_ERRORS - 1)
    assert queue.pending() == [bad]
    record = json.loads((queue.pending_dir / f"{bad.stem}.failures.json").read_text())
    assert record["status_code"] == 501 and record["count"] == HOLD_AFTER_SERVER_ERRORS - 1


def test_the_upload_command_exits_0_once_the_failing_file_is_held(tmp_path, monkeypatch, capsys) -> None:
    from kinect_agent.commands import upload as command
    from kinect_agent.config import AgentConfig, save_config

    monkeypatch.setenv("KINECT_AGENT_HOME", str(tmp_path / "home"))
    save_config(AgentConfig(server_url="http://coach.test", device_token="khd_x", queue_dir=str(tmp_path / "queue")))
    queue, (bad, _, _) = _queue_three(tmp_path)
    server = Server({bad.read_bytes()}, 500)
    real = command.upload_queue
    monkeypatch.setattr(command, "upload_queue", lambda **kw: real(transport=server, **kw))
    monkeypatch.setattr("kinect_agent.upload.RetryPolicy", lambda: FAST)
    codes = [command.run(command_args()) for _ in range(HOLD_AFTER_SERVER_ERRORS + 1)]
    assert codes == [1] * HOLD_AFTER_SERVER_ERRORS + [0], codes
    assert "set aside in held/" in capsys.readouterr().err


def command_args():
    import argparse

    return argparse.Namespace(once=True, interval=30.0, retry_rejected=False, retry_held=False)


def test_a_raw_copy_whose_process_died_is_queued_at_once(tmp_path) -> None:
    root = tmp_path / "queue"
    script = textwrap.dedent(f"""
        import sys, os
        sys.path.insert(0, {str(REPO)!r})
        import numpy as np, uuid
        from tests.kinect_agent.test_held_sessions import session_payload
        from kinect_agent.queue import SessionQueue
        q = SessionQueue({str(root)!r})
        q.hold(session_payload(7))
        os._exit(0)  # killed while filtering: no release
    """)
    subprocess.run([sys.executable, "-c", script], check=True, timeout=60)
    (held,) = (root / "captured").glob("*.khs")
    recovered = SessionQueue(root).recover_held()  # default age rule: 30 minutes
    assert recovered == [root / "pending" / held.name] and not held.exists()


@pytest.mark.skipif(importlib.util.find_spec("fcntl") is None, reason="flock: POSIX only")
def test_a_raw_copy_a_living_process_is_filtering_stays_with_it(tmp_path) -> None:
    root = tmp_path / "queue"
    working = SessionQueue(root)
    working.hold(session_payload(8))
    assert SessionQueue(root).recover_held(older_than_s=0) == []  # another queue object: another open file
    assert working.recover_held(older_than_s=0) == []  # nor its own while it works on it


def test_a_raw_copy_of_a_session_already_stored_is_dropped_not_queued_again(tmp_path) -> None:
    """Killed between the server's confirmation and dropping the raw copy: queuing the copy again would be other
    content under the same session id, refused as a conflict and shown as "rejected"."""
    root = tmp_path / "queue"
    queue = SessionQueue(root)
    payload = session_payload(9)
    queue.hold(payload)
    pending = queue.enqueue(payload.__class__(session_id=payload.session_id, raw=payload.raw, params={"filtered": 1}))
    queue.mark_sent(pending, {"status_code": 201})
    queue._locks.pop(payload.session_id).close()  # the process dies here, before release()
    assert SessionQueue(root).recover_held() == []
    assert list((root / "captured").glob("*.khs")) == [] and queue.pending() == []
    assert queue.where(payload.session_id) == "sent"
