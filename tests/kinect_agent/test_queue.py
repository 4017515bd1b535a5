"""The disk queue: durable, atomic, crash-safe; a file leaves pending/ only with a receipt or a rejection."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import uuid
from pathlib import Path

import numpy as np
import pytest

from kinect_agent import skeleton
from kinect_agent.formats.session_file import SessionPayload, encode, read_payload
from kinect_agent.queue import QueueError, SessionQueue
from kinect_agent.recording import Metadata, Recording

REPO = Path(__file__).resolve().parents[2]


def _payload(seed: int = 0, session_id: str | None = None) -> SessionPayload:
    rng = np.random.default_rng(seed)
    t = np.arange(30) / 30.0
    positions = rng.normal(0.0, 0.3, (30, skeleton.J, 3)) + [0.0, 0.0, 2.5]
    rec = Recording.from_positions(t, positions, Metadata(device="simulator", exercise="squat"))
    return SessionPayload(session_id=session_id or str(uuid.uuid4()), raw=rec)


def test_enqueue_writes_pending_file_named_by_session_id(tmp_path) -> None:
    queue = SessionQueue(tmp_path / "q")
    payload = _payload()
    path = queue.enqueue(payload)
    assert path == tmp_path / "q" / "pending" / f"{payload.session_id}.khs"
    assert read_payload(path).session_id == payload.session_id
    assert queue.pending() == [path]


def test_pending_lists_oldest_first(tmp_path) -> None:
    queue = SessionQueue(tmp_path)
    paths = [queue.enqueue(_payload(i)) for i in range(3)]
    for k, p in enumerate(paths):
        os.utime(p, ns=(10**18 - k * 10**9, 10**18 - k * 10**9))  # the last enqueued is the oldest now
    assert queue.pending() == paths[::-1]


def test_same_bytes_twice_is_a_no_op_and_different_bytes_are_refused(tmp_path) -> None:
    queue = SessionQueue(tmp_path)
    payload = _payload()
    data = encode(payload)
    first = queue.enqueue_bytes(payload.session_id, data)
    assert queue.enqueue_bytes(payload.session_id, data) == first
    with pytest.raises(QueueError, match="already queued with different content"):
        queue.enqueue(_payload(seed=1, session_id=payload.session_id))
    assert first.read_bytes() == data


def test_unsafe_session_id_is_refused(tmp_path) -> None:
    with pytest.raises(QueueError, match="cannot name a queue file"):
        SessionQueue(tmp_path).enqueue(_payload(session_id="../../etc/passwd"))


def test_error_during_enqueue_leaves_nothing_in_pending(tmp_path, monkeypatch) -> None:
    queue = SessionQueue(tmp_path)

    def broken_fsync(fd: int) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "fsync", broken_fsync)
    with pytest.raises(OSError, match="No space left"):
        queue.enqueue(_payload())
    assert list((tmp_path / "pending").iterdir()) == []


def test_crash_in_the_middle_of_enqueue_leaves_no_partial_file_in_pending(tmp_path) -> None:
    """A process killed (SIGKILL) between writing and renaming leaves only a temp file, never a queued one."""
    script = textwrap.dedent(f"""
        import os, signal, sys
        sys.path.insert(0, {str(REPO)!r})
        sys.path.insert(0, {str(Path(__file__).parent)!r})
        from test_queue import _payload
        from kinect_agent.queue import SessionQueue
        queue = SessionQueue({str(tmp_path)!r})
        os.fsync = lambda fd: os.kill(os.getpid(), signal.SIGKILL)  # dies after write, before the rename
        queue.enqueue(_payload())
    """)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert proc.returncode == -9, proc.stderr
    queue = SessionQueue(tmp_path)
    leftovers = list((tmp_path / "pending").iterdir())
    assert len(leftovers) == 1 and leftovers[0].name.endswith(".part"), leftovers
    assert queue.pending() == []
    assert queue.clean_partial(older_than_s=3600) == []  # a fresh temp file may belong to a running write
    assert queue.clean_partial(older_than_s=0) == leftovers
    assert list((tmp_path / "pending").iterdir()) == []


def test_mark_sent_writes_the_receipt_then_removes_the_file(tmp_path) -> None:
    queue = SessionQueue(tmp_path)
    payload = _payload()
    path = queue.enqueue(payload)
    queue.mark_sent(path, {"status_code": 201, "server_session_id": 7})
    assert not path.exists() and queue.pending() == []
    receipt = queue.receipt(payload.session_id)
    assert receipt is not None
    assert receipt["server_session_id"] == 7 and receipt["status_code"] == 201
    assert queue.counts().sent == 1


def test_keep_sent_moves_the_file_to_sent(tmp_path) -> None:
    queue = SessionQueue(tmp_path, keep_sent=True)
    path = queue.enqueue(_payload())
    queue.mark_sent(path, {"status_code": 200})
    assert (tmp_path / "sent" / path.name).exists()


def test_mark_rejected_keeps_file_and_error_and_requeue_brings_it_back(tmp_path) -> None:
    queue = SessionQueue(tmp_path)
    payload = _payload()
    path = queue.enqueue(payload)
    target = queue.mark_rejected(path, {"status_code": 400, "detail": "InvalidSessionFile: bad_magic: ..."})
    assert target.read_bytes() == encode(payload)
    assert queue.pending() == [] and queue.counts().rejected == 1
    rejection = queue.rejection(payload.session_id)
    assert rejection is not None and rejection["status_code"] == 400
    assert queue.requeue_rejected() == [path]
    assert queue.pending() == [path] and queue.rejection(payload.session_id) is None


def test_mark_sent_refuses_a_file_outside_pending(tmp_path) -> None:
    queue = SessionQueue(tmp_path / "q")
    stray = tmp_path / "x.khs"
    stray.write_bytes(b"")
    with pytest.raises(QueueError, match="not a file of the queue"):
        queue.mark_sent(stray, {})


def test_held_session_is_recovered_after_a_crash(tmp_path) -> None:
    queue = SessionQueue(tmp_path)
    payload = _payload()
    queue.hold(payload)
    assert queue.pending() == []
    assert queue.recover_held() == [], "a held file this process is filtering right now stays with it"
    lock = queue._locks.pop(payload.session_id, None)
    if lock is not None:
        lock.close()  # the process dies: its lock goes with it
    recovered = SessionQueue(tmp_path).recover_held(older_than_s=0)
    assert recovered == [tmp_path / "pending" / f"{payload.session_id}.khs"]
    assert read_payload(recovered[0]).session_id == payload.session_id
    assert list((tmp_path / "captured").iterdir()) == []
    assert queue.where(payload.session_id) == "pending" and queue.where("unknown-id") is None


def test_without_flock_held_files_are_recovered_by_age(tmp_path, monkeypatch) -> None:
    import kinect_agent.queue as module

    monkeypatch.setattr(module, "fcntl", None)  # as on Windows
    queue = SessionQueue(tmp_path)
    payload = _payload()
    queue.hold(payload)
    assert SessionQueue(tmp_path).recover_held() == [], "younger than 30 minutes: maybe still being filtered"
    assert SessionQueue(tmp_path).recover_held(older_than_s=0) == [tmp_path / "pending" / f"{payload.session_id}.khs"]
