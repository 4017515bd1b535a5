"""What live progress a device may post: at most MAX_PER_WINDOW "recording" messages per WINDOW_S, and no message
twice in a row (the same content again is answered 204 but not passed on).

The agent sends a "recording" message every 0.2 s (kinect_agent.live.set_recorder, 5 a second) and each set's end
("ended" or "failed") once; the limit leaves it twice that. A set's end is never limited (it carries the result the
page waits for), only deduplicated. State is per server process (each worker limits on its own, so a device gets at
most workers × the limit), for the MAX_DEVICES devices heard from most recently.
"""

from __future__ import annotations

import threading
import time
from collections import OrderedDict, deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from backend.exceptions import AppError

MAX_PER_WINDOW = 10
WINDOW_S = 1.0
MAX_DEVICES = 10_000


class LiveProgressTooFast(AppError):
    """A device posts live progress faster than the agent ever does."""

    status_code = 429


@dataclass
class _DeviceState:
    times: deque[float] = field(default_factory=deque)  # monotonic times of the recent "recording" messages
    last: dict[str, Any] | None = None  # the last message passed on


class ProgressGate:
    """Per-device rate limit and deduplication of live progress messages (thread-safe)."""

    def __init__(self, max_per_window: int = MAX_PER_WINDOW, window_s: float = WINDOW_S,
                 clock: Callable[[], float] = time.monotonic) -> None:  # fmt: skip
        self.max_per_window = max_per_window
        self.window_s = window_s
        self.clock = clock
        self._devices: OrderedDict[int, _DeviceState] = OrderedDict()
        self._lock = threading.Lock()

    def admit(self, device_id: int, message: dict[str, Any]) -> bool:
        """Returns True when the message is to be passed on, False when it repeats the device's last one; raises
        LiveProgressTooFast for a "recording" message over the limit."""
        now = self.clock()
        with self._lock:
            state = self._devices.pop(device_id, None) or _DeviceState()
            self._devices[device_id] = state
            while len(self._devices) > MAX_DEVICES:
                self._devices.popitem(last=False)
            if message == state.last:
                return False
            if message.get("state") == "recording":
                while state.times and state.times[0] <= now - self.window_s:
                    state.times.popleft()
                if len(state.times) >= self.max_per_window:
                    raise LiveProgressTooFast(
                        f"live progress: at most {self.max_per_window} messages per {self.window_s:g} s per device",
                        headers={"Retry-After": "1"},
                    )
                state.times.append(now)
            state.last = message
            return True
