"""One set, recorded on the server's command: frames in, live feedback out, the frames kept on disk.

Each frame goes to the journal (disk) first, then through the online filter (online.live_filter: the chain's, or the
webcam's joints filter) and the live count (kinect_agent.analysis.live.LiveCount, the server's repetition logic run
incrementally). A "starting" message answers the Start before the source is opened; then every `every_s` seconds a
progress message is offered to the publisher (which never blocks). The set ends when
    "target"  the count reached the target and settle_s more seconds were recorded (the return to rest);
    "stop"    stop() was called (the patient pressed Stop, or the agent is shutting down);
    "still"   the defining angle did not move for still_end_s seconds (the patient walked away or gave up);
    "limit"   max_s seconds were recorded;
    "source"  the source ended (a replayed file).
"""

from __future__ import annotations

import threading
import time
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from kinect_agent.analysis.live import LiveCount, LiveStatus
from kinect_agent.clock import utc_now_iso
from kinect_agent.live.journal import Journal
from kinect_agent.processing.config import config_for_device
from kinect_agent.processing.online import live_filter
from kinect_agent.recording import Metadata, Recording
from kinect_agent.sources.base import Source


@dataclass(frozen=True)
class SetCommand:
    """What the server asked for: set_id, the exercise, its target repetitions and defining angles."""

    set_id: str
    exercise: str
    target_reps: int
    angles: tuple[str, ...]

    @classmethod
    def from_message(cls, data: dict[str, Any]) -> SetCommand:
        """Returns the command in a live.command start message; raises ValueError naming a bad field."""
        missing = [k for k in ("set_id", "exercise_slug", "target_reps", "angles") if k not in data]
        if missing:
            raise ValueError(f"start command without {', '.join(missing)}")
        try:
            set_id = str(uuid.UUID(str(data["set_id"])))
        except ValueError:
            raise ValueError(f"start command with a bad set_id {data['set_id']!r}") from None
        exercise, target, angles = data["exercise_slug"], data["target_reps"], data["angles"]
        if not isinstance(exercise, str) or not isinstance(target, int) or target < 1:
            raise ValueError(f"start command with a bad exercise {exercise!r} or target {target!r}")
        if not isinstance(angles, list) or not angles or not all(isinstance(a, str) for a in angles):
            raise ValueError(f"start command with bad angles {angles!r}")
        return cls(set_id, exercise, target, tuple(angles))


@dataclass
class SetLimits:
    """When a set ends by itself (seconds)."""

    settle_s: float = 1.0
    still_end_s: float = 20.0
    max_s: float = 900.0
    every_s: float = 0.2  # progress messages: 5 a second


@dataclass
class SetResult:
    """How a set ended: the reason, the live count, the session id and the recorded frames (None if no frame)."""

    reason: str
    count: int
    session_id: str
    created_at: str
    recording: Recording | None
    journal: Journal | None = field(default=None, repr=False)


def failed_message(command: SetCommand, hint: str) -> dict[str, Any]:
    """Returns the progress message that says a set could not be recorded, in plain words (hint)."""
    return {"set_id": command.set_id, "exercise_slug": command.exercise, "state": "failed", "count": 0, "hint": hint,
            "sent_at": time.time()}  # fmt: skip


class SetRecorder:
    """Records one set from `source` into a journal in journal_dir, publishing progress while it runs."""

    def __init__(
        self,
        command: SetCommand,
        source: Source,
        journal_dir: Path,
        publish: Callable[[dict[str, Any], bool], None],
        limits: SetLimits | None = None,
    ) -> None:
        self.command = command
        self.source = source
        self.journal_dir = journal_dir
        self.publish = publish
        self.limits = limits or SetLimits()
        self.session_id = str(uuid.uuid4())
        self._stop = threading.Event()

    def stop(self) -> None:
        """Ends the set at the next frame (its frames are kept)."""
        self._stop.set()

    def _message(
        self, state: str, status: LiveStatus | None, elapsed: float, taken_at: float, **extra: Any
    ) -> dict[str, Any]:
        """Returns a progress message; taken_at: wall clock (Unix s) when its frame arrived (for the latency)."""
        c = self.command
        msg = {"set_id": c.set_id, "exercise_slug": c.exercise, "state": state, "target": c.target_reps,
               "count": status.count if status else 0, "elapsed_s": round(elapsed, 2), "session_id": self.session_id,
               "sent_at": taken_at}  # fmt: skip
        if status is not None:
            angle = status.angle_deg
            msg |= {"angle_name": status.angle_name, "angle_deg": None if angle is None else round(angle, 1),
                    "hint": status.hint}  # fmt: skip
        return msg | extra

    def _metadata(self) -> Metadata:
        """Returns the source's metadata now, with the commanded exercise and the live set's id."""
        meta = self.source.metadata()
        meta.exercise = self.command.exercise
        meta.extra["live_set_id"] = self.command.set_id
        return meta

    def _end_reason(self, status: LiveStatus, elapsed: float, target_since: float | None) -> str | None:
        lim = self.limits
        if self._stop.is_set():
            return "stop"
        if target_since is not None and elapsed - target_since >= lim.settle_s:
            return "target"
        if status.still_s >= lim.still_end_s and elapsed >= lim.still_end_s:
            return "still"
        if elapsed >= lim.max_s:
            return "limit"
        return None

    def run(self) -> SetResult:
        """Records until the set ends; returns the result (the journal is still on disk: discard it once queued)."""
        created_at = utc_now_iso()
        # the Start is answered at once: opening the camera and the filter's first step can take many seconds (its
        # compiled code is still being readied on a busy computer), and the page must not take that for silence
        self.publish(self._message("starting", None, 0.0, time.time()), False)
        with self.source:
            meta = self._metadata()
            journal = Journal(self.journal_dir, self.session_id, meta, created_at)
            online, counter = (
                live_filter(config_for_device(meta.device)),
                LiveCount(self.command.angles, device=meta.device),
            )
            status, reason, t0, target_since, last_sent = None, "source", None, None, -1e9
            for frame in self.source.frames():
                taken_at = time.time()
                journal.append(frame.t, frame.positions, frame.state)
                t0 = frame.t if t0 is None else t0
                elapsed = frame.t - t0
                status = counter.add(frame.t, frame.positions, frame.state,
                                     online.step(frame.t, frame.positions, frame.state))  # fmt: skip
                if target_since is None and status.count >= self.command.target_reps:
                    target_since = elapsed
                if (ended := self._end_reason(status, elapsed, target_since)) is not None:
                    reason = ended
                    break
                if time.monotonic() - last_sent >= self.limits.every_s:
                    self.publish(self._message("recording", status, elapsed, taken_at), False)
                    last_sent = time.monotonic()
            # the header as the set ended: a webcam's frame rate achieved, image size and images analysed are known
            # only now (the journal's header on disk keeps the opening one, enough for a set a crash interrupts)
            journal.meta = self._metadata()
        recording = journal.finish()
        count = counter.final() if recording is not None else 0
        elapsed = recording.duration if recording is not None else 0.0
        self.publish(self._message("ended", status, elapsed, time.time(), reason=reason, count=count), True)
        return SetResult(reason, count, self.session_id, created_at, recording, journal)
