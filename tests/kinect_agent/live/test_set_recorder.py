"""One live set: how it ends (target, Stop, no movement, end of the source) and what it publishes on the way."""

from __future__ import annotations

import uuid
from typing import Any

import numpy as np
import pytest

from kinect_agent import formats
from kinect_agent.analysis.exercise import EXERCISES
from kinect_agent.live.set_recorder import SetCommand, SetLimits, SetRecorder
from kinect_agent.recording import Recording
from kinect_agent.sources.replay import ReplaySource
from kinect_agent.sources.simulator import simulate


def _source(tmp_path, rec: Recording) -> ReplaySource:
    path = tmp_path / "set.csv"
    formats.write(rec, path)
    return ReplaySource(path, realtime=False)


def _command(exercise: str, target: int) -> SetCommand:
    return SetCommand(str(uuid.uuid4()), exercise, target, tuple(EXERCISES[exercise].defining_angles))


def _record(tmp_path, rec, command, limits=None, on_message=None):
    messages = []

    def publish(message: dict[str, Any], keep: bool) -> None:
        messages.append((message, keep))
        if on_message:
            on_message(message, recorder)

    recorder = SetRecorder(command, _source(tmp_path, rec), tmp_path / "recording", publish, limits)
    return recorder.run(), messages


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_set_ends_when_the_target_is_reached(tmp_path, seed):
    rec = simulate("elbow_flexion", 5, seed=seed)[0]
    result, messages = _record(tmp_path, rec, _command("elbow_flexion", 3), SetLimits(every_s=0.0))
    assert result.reason == "target" and result.count == 3, (result.reason, result.count)
    assert result.recording.n_frames < rec.n_frames  # it stopped recording before the source ended
    counts = [m["count"] for m, _ in messages]
    assert counts == sorted(counts) and counts[-1] == 3
    first, keep = messages[0]  # the Start is answered before the first frame is counted
    assert first["state"] == "starting" and first["count"] == 0 and first["session_id"] == result.session_id
    assert {m["state"] for m, _ in messages[1:-1]} == {"recording"}
    last, keep = messages[-1]
    assert keep and last["state"] == "ended" and last["reason"] == "target"
    assert last["session_id"] == result.session_id and all(m["set_id"] == messages[0][0]["set_id"] for m, _ in messages)
    np.testing.assert_allclose(result.recording.t, rec.t[: result.recording.n_frames], atol=1e-6)  # journal frames


def test_a_set_ends_after_a_stretch_without_movement(tmp_path):
    one = simulate("squat", 1, seed=3)[0]
    n = 30 * 12  # 12 s of one pose
    still = Recording(np.arange(n) / 30.0, np.repeat(one.positions[:1], n, 0), np.repeat(one.state[:1], n, 0), one.meta)
    result, messages = _record(tmp_path, still, _command("squat", 10), SetLimits(still_end_s=5.0))
    assert result.reason == "still" and result.count == 0
    assert 5.0 <= result.recording.duration <= 6.0


def test_stop_ends_the_set_and_keeps_what_was_recorded(tmp_path):
    rec = simulate("shoulder_abduction", 4, seed=2)[0]

    def on_message(message, recorder):
        if message["state"] == "recording" and message["elapsed_s"] >= 4.0:
            recorder.stop()

    result, messages = _record(tmp_path, rec, _command("shoulder_abduction", 10), SetLimits(every_s=0.0), on_message)
    assert result.reason == "stop" and 4.0 <= result.recording.duration < 5.0
    assert messages[-1][0]["reason"] == "stop"


def test_a_replayed_file_that_ends_ends_the_set(tmp_path):
    rec = simulate("elbow_flexion", 2, seed=4)[0]
    result, _ = _record(tmp_path, rec, _command("elbow_flexion", 10))
    assert result.reason == "source" and result.count == 2 and result.recording.n_frames == rec.n_frames


@pytest.mark.parametrize(
    ("data", "field"),
    [
        ({"set_id": "x"}, "set_id"),
        ({"target_reps": 0}, "target"),
        ({"angles": []}, "angles"),
        ({"exercise_slug": None}, "exercise"),
    ],
)
def test_a_bad_start_command_is_refused_naming_the_field(data, field):
    good = {"set_id": str(uuid.uuid4()), "exercise_slug": "squat", "target_reps": 5, "angles": ["knee_flexion_L"]}
    with pytest.raises(ValueError, match=field):
        SetCommand.from_message(good | data)
