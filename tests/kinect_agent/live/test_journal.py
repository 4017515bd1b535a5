"""The set journal: frames on disk while a set is recorded, and what a crash leaves behind."""

from __future__ import annotations

import uuid

import numpy as np
import pytest

from kinect_agent.capture import queue_session
from kinect_agent.commands.serve import recover_interrupted
from kinect_agent.formats.session_file import decode
from kinect_agent.live import journal
from kinect_agent.live.journal import RECORD, Journal
from kinect_agent.queue import SessionQueue
from kinect_agent.sources.simulator import simulate


def _write(folder, rec, n=None, session_id=None):
    session_id = session_id or str(uuid.uuid4())
    j = Journal(folder, session_id, rec.meta, "2026-11-25T10:00:00Z")
    for i in range(rec.n_frames if n is None else n):
        j.append(rec.t[i], rec.positions[i], rec.state[i])
    j.flush()
    return j


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_finish_returns_the_frames_exactly(tmp_path, seed):
    rec = simulate("elbow_flexion", 2, seed=seed)[0]
    out = _write(tmp_path, rec).finish()
    np.testing.assert_array_equal(out.t, rec.t)
    np.testing.assert_array_equal(out.positions, rec.positions)  # NaN where untracked, in the same places
    np.testing.assert_array_equal(out.state, rec.state)


def test_a_crash_keeps_a_long_enough_set_and_drops_a_torn_record(tmp_path):
    rec = simulate("squat", 2, seed=3)[0]
    j = _write(tmp_path / "recording", rec, n=200)  # about 6.6 s at 30 Hz; then the process dies
    with open(j.frames_path, "ab") as f:
        f.write(b"\x01" * (RECORD.itemsize // 2))  # half a record: the write the crash interrupted
    (found,) = journal.recover(tmp_path / "recording")
    assert found.recording is not None and found.recording.n_frames == 200
    assert found.recording.meta.extra["interrupted"] is True
    queue = SessionQueue(tmp_path / "queue")
    assert recover_interrupted(queue, tmp_path / "recording") == 1
    (pending,) = queue.pending()
    payload = decode(pending.read_bytes())
    assert payload.session_id == j.session_id and payload.raw.n_frames == 200
    assert payload.filtered is not None  # filtered like any finished set
    assert list((tmp_path / "recording").iterdir()) == []  # the journal is gone once the set is queued


def test_a_fragment_shorter_than_the_rule_is_dropped(tmp_path):
    rec = simulate("squat", 2, seed=4)[0]
    _write(tmp_path / "recording", rec, n=int(journal.MIN_KEEP_S * 30) - 10)
    queue = SessionQueue(tmp_path / "queue")
    assert recover_interrupted(queue, tmp_path / "recording") == 0
    assert queue.pending() == [] and list((tmp_path / "recording").iterdir()) == []


def test_an_unreadable_header_is_reported_and_removed(tmp_path):
    folder = tmp_path / "recording"
    folder.mkdir()
    (folder / "abc.json").write_text("{not json")
    (found,) = journal.recover(folder)
    assert found.recording is None and found.reason.startswith("unreadable")
    assert recover_interrupted(SessionQueue(tmp_path / "queue"), folder) == 0
    assert list(folder.iterdir()) == []


def test_a_set_queued_whole_before_its_journal_was_removed_stays_as_queued(tmp_path):
    """A stop (Ctrl-C, power) between queuing an ended set and removing its journal: on the next start the queued
    file is the set, the journal is dropped, and the agent starts (it used to stop with "already queued with
    different content", so the home computer never came back)."""
    rec = simulate("seated_knee_extension", 2, seed=5)[0]
    j = _write(tmp_path / "recording", rec)
    queue = SessionQueue(tmp_path / "queue")
    queued = queue_session(queue, rec, session_id=j.session_id, created_at="2026-11-25T10:00:00Z")
    before = queued.read_bytes()
    assert recover_interrupted(queue, tmp_path / "recording") == 0
    assert queue.pending() == [queued] and queued.read_bytes() == before
    assert list((tmp_path / "recording").iterdir()) == []
