"""The agent's connection to the server for the live loop; the agent opens it, nothing listens at home.

CommandStream: GET /api/v1/live/agent, a server-sent-event stream of commands ("start"/"stop" a set), held open
and reopened after any failure with backoff (1 s doubling to 30 s, full jitter; 60 s when the token is refused).
While it is open the server shows the patient's page that the home computer is ready.
Publisher: POST /api/v1/live/progress from a thread of its own, so recording never waits for the network. Only the
newest progress message waits to be sent (older ones are dropped); messages marked `keep` (a set's end) are sent
in order. A message that fails is dropped: live messages are a courtesy; the session itself goes through the queue.
"""

from __future__ import annotations

import collections
import json
import random
import threading
from collections.abc import Callable, Iterator
from typing import Any

import httpx

from kinect_agent import __version__

COMMANDS_PATH = "/api/v1/live/agent"
PROGRESS_PATH = "/api/v1/live/progress"
READ_TIMEOUT_S = 45.0  # the server sends a keep-alive every 15 s: three missed means the connection is dead
MAX_BACKOFF_S = 30.0
REFUSED_BACKOFF_S = 60.0


def _headers(token: str) -> dict[str, str]:
    return {"Authorization": f"Bearer {token}", "User-Agent": f"kinect-agent/{__version__}"}


def parse_events(lines: Iterator[str]) -> Iterator[tuple[str, str]]:
    """Yields (event name, data) of a server-sent-event stream given line by line (comments skipped)."""
    name, data = "message", list[str]()
    for line in lines:
        if not line:
            if data:
                yield name, "\n".join(data)
            name, data = "message", []
        elif line.startswith(":"):
            continue
        else:
            field, _, value = line.partition(":")
            value = value[1:] if value.startswith(" ") else value
            if field == "event":
                name = value
            elif field == "data":
                data.append(value)


class CommandStream:
    """Yields the server's commands to this device for as long as `stop` is not set, reconnecting as needed."""

    def __init__(
        self,
        server_url: str,
        token: str,
        *,
        log: Callable[[str], None] = print,
        transport: httpx.BaseTransport | None = None,
        seed: int | None = None,
    ) -> None:
        self.url = server_url.rstrip("/") + COMMANDS_PATH
        self.token = token
        self.log = log
        self.connected = threading.Event()
        self._rng = random.Random(seed)
        timeout = httpx.Timeout(10.0, read=READ_TIMEOUT_S)
        self._client = httpx.Client(timeout=timeout, headers=_headers(token), transport=transport)

    def close(self) -> None:
        """Closes the connection (a blocked read ends with an error)."""
        self._client.close()

    def commands(self, stop: threading.Event) -> Iterator[dict[str, Any]]:
        """Yields each command's data dict ({"action": "start"|"stop", "set_id", ...}) until stop is set."""
        attempt = 0
        while not stop.is_set():
            wait = None
            try:
                with self._client.stream("GET", self.url) as response:
                    if response.status_code in (401, 403):
                        self.log(f"live: the server refused this device ({response.status_code}); pair it again")
                        wait = REFUSED_BACKOFF_S
                    elif response.status_code != 200:
                        self.log(f"live: the server answered {response.status_code}; retrying")
                    else:
                        attempt = 0
                        self.connected.set()
                        self.log(f"live: connected to {self.url}")
                        for name, data in parse_events(response.iter_lines()):
                            if stop.is_set():
                                return
                            command = _command(name, data)
                            if command is not None:
                                yield command
                        self.log("live: the server closed the stream; reconnecting")
            except (httpx.HTTPError, OSError) as exc:
                if stop.is_set():
                    return
                self.log(f"live: no connection to the server ({type(exc).__name__}); retrying")
            finally:
                self.connected.clear()
            delay = wait if wait is not None else self._rng.uniform(0.5, min(MAX_BACKOFF_S, 2.0**attempt))
            attempt = min(attempt + 1, 10)
            stop.wait(delay)


def _command(name: str, data: str) -> dict[str, Any] | None:
    """Returns the command in one event (kind live.command), or None for anything else."""
    if name != "live.command":
        return None
    try:
        payload = json.loads(data).get("data")
    except (ValueError, AttributeError):
        return None
    if not isinstance(payload, dict) or payload.get("action") not in ("start", "stop"):
        return None
    return payload


class Publisher:
    """Posts progress messages from a background thread; `offer` never blocks."""

    def __init__(
        self,
        server_url: str,
        token: str,
        *,
        log: Callable[[str], None] = print,
        transport: httpx.BaseTransport | None = None,
    ) -> None:
        self.url = server_url.rstrip("/") + PROGRESS_PATH
        self.log = log
        self._client = httpx.Client(timeout=httpx.Timeout(3.0), headers=_headers(token), transport=transport)
        self._latest: dict[str, Any] | None = None
        self._kept: collections.deque[dict[str, Any]] = collections.deque(maxlen=100)
        self._cond = threading.Condition()
        self._closed = False
        self.sent = self.dropped = 0
        self._failing = False
        self._thread = threading.Thread(target=self._run, name="live-publisher", daemon=True)
        self._thread.start()

    def offer(self, message: dict[str, Any], *, keep: bool = False) -> None:
        """Queues a message; keep=False replaces a not yet sent ordinary message."""
        with self._cond:
            if keep:
                self._kept.append(message)
            else:
                if self._latest is not None:
                    self.dropped += 1
                self._latest = message
            self._cond.notify()

    def close(self, timeout: float = 5.0) -> None:
        """Sends what is waiting (up to timeout seconds), then stops."""
        with self._cond:
            self._closed = True
            self._cond.notify()
        self._thread.join(timeout)
        self._client.close()

    def _next(self) -> dict[str, Any] | None:
        with self._cond:
            while not self._kept and self._latest is None and not self._closed:
                self._cond.wait()
            if self._kept:
                return self._kept.popleft()
            message, self._latest = self._latest, None
            return message

    def _run(self) -> None:
        while (message := self._next()) is not None:
            try:
                response = self._client.post(self.url, json=message)
                ok = response.status_code < 300
                detail = f"HTTP {response.status_code}: {response.text[:200]}"
            except (httpx.HTTPError, OSError) as exc:
                ok, detail = False, type(exc).__name__
            if ok:
                self.sent += 1
                self._failing = False
            else:
                self.dropped += 1
                if not self._failing:  # once per outage
                    self.log(f"live: a progress message was not delivered ({detail})")
                self._failing = True
