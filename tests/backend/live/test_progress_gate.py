"""Live progress is rate-limited and deduplicated per device (backend/live/progress_gate.py)."""

from __future__ import annotations

from typing import Any

import pytest

from backend.live.progress_gate import MAX_PER_WINDOW, LiveProgressTooFast, ProgressGate


def _msg(count: int = 1, state: str = "recording", set_id: str = "s") -> dict[str, Any]:
    return {"set_id": set_id, "exercise_slug": "squat", "state": state, "count": count}


class _Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def test_more_than_the_limit_per_second_is_refused_then_allowed_again():
    clock = _Clock()
    gate = ProgressGate(clock=clock)
    assert all(gate.admit(1, _msg(i)) for i in range(MAX_PER_WINDOW))
    with pytest.raises(LiveProgressTooFast):
        gate.admit(1, _msg(99))
    assert gate.admit(2, _msg(99)), "another device has its own limit"
    assert gate.admit(1, _msg(7, state="ended")), "a set's end is never limited"
    clock.now += 1.0
    assert gate.admit(1, _msg(100))


def test_the_same_message_twice_is_passed_on_once():
    gate = ProgressGate(clock=_Clock())
    assert gate.admit(1, _msg(3)) is True
    assert gate.admit(1, _msg(3)) is False
    assert gate.admit(1, _msg(4)) is True
    assert gate.admit(1, _msg(3)) is True, "only a repeat of the last message is dropped"
