"""Capture sources: anything that yields skeleton frames (a device, a file replay, the simulator).

A source is opened, yields Frame objects, and is closed; `record(source, seconds)` collects its frames into a
Recording. Sources are context managers: `with source: ...` opens and closes them.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Protocol, Self, runtime_checkable

import numpy as np

from kinect_agent import skeleton
from kinect_agent.errors import AgentError
from kinect_agent.recording import Metadata, Recording


@dataclass(frozen=True)
class Frame:
    """One skeleton frame: t float s (source clock); positions (J, 3) m, camera frame, NaN = untracked; state (J,)."""

    t: float
    positions: np.ndarray
    state: np.ndarray


@runtime_checkable
class Source(Protocol):
    """What the agent needs from a capture source."""

    name: str  # e.g. "replay", "simulator", "kinect_v2"
    device: str  # one of kinect_agent.recording.DEVICES

    def open(self) -> None:
        """Acquires the device or file; raises DeviceUnavailable or FormatError with a clear message."""

    def frames(self) -> Iterator[Frame]:
        """Yields frames in time order until the source ends (files) or forever (devices)."""

    def close(self) -> None:
        """Releases the device; safe to call twice."""

    def metadata(self) -> Metadata:
        """Returns what is known about the recording this source makes."""

    def __enter__(self) -> Self:
        """Opens the source (`with source:` as the recorders use it)."""

    def __exit__(self, *exc: object) -> None:
        """Closes the source."""


class SourceBase:
    """Context-manager plumbing shared by the sources."""

    name = "source"
    device = "unknown"

    def open(self) -> None:  # pragma: no cover - overridden
        raise NotImplementedError

    def close(self) -> None:
        return None

    def __enter__(self) -> Self:
        self.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class Pacer:
    """Sleeps so that frames with source times t come out at real-time pace (no sleeping when realtime is False)."""

    def __init__(self, realtime: bool) -> None:
        self.realtime = realtime
        self._start_wall: float | None = None
        self._start_t = 0.0

    def wait(self, t: float) -> None:
        """Blocks until the wall clock reaches source time t (relative to the first call)."""
        if not self.realtime:
            return
        now = time.monotonic()
        if self._start_wall is None:
            self._start_wall, self._start_t = now, t
            return
        delay = (t - self._start_t) - (now - self._start_wall)
        if delay > 0:
            time.sleep(delay)


def record(source: Source, seconds: float) -> Recording:
    """Opens `source`, collects frames until `seconds` of source time have passed (or it ends), closes it.

    Frame times are made relative to the first frame; frames that do not advance the clock are dropped.
    Raises AgentError when the source gave no frame at all.
    """
    if not (isinstance(seconds, (int, float)) and np.isfinite(seconds) and seconds > 0):
        raise ValueError(f"seconds must be a positive number, got {seconds!r}")
    times: list[float] = []
    positions: list[np.ndarray] = []
    states: list[np.ndarray] = []
    source.open()
    try:
        for frame in source.frames():
            pos = np.asarray(frame.positions, dtype=np.float64)
            if pos.shape != (skeleton.J, 3):
                raise ValueError(
                    f"source {source.name}: frame positions must have shape ({skeleton.J}, 3), got {pos.shape}"
                )
            if times and frame.t <= times[-1]:
                continue
            if times and frame.t - times[0] > seconds:
                break
            times.append(float(frame.t))
            positions.append(pos)
            states.append(np.asarray(frame.state, dtype=np.int8))
        meta = source.metadata()
    finally:
        source.close()
    if not times:
        raise AgentError(f"source {source.name} gave no frames")
    t = np.asarray(times) - times[0]
    meta.history.append(f"record(source={source.name}, seconds={seconds})")
    return Recording(t, np.stack(positions), np.stack(states), meta)
