"""The agent's live connection: server-sent events parsed, commands picked out, progress never blocking."""

from __future__ import annotations

import json
import threading
import time
from typing import Any

import httpx

from kinect_agent.live.channel import CommandStream, Publisher, parse_events


def _sse(*events: tuple[str, dict[str, Any]]) -> str:
    body = "retry: 3000\n: connected\n\n"
    for name, data in events:
        body += f"event: {name}\ndata: {json.dumps(data)}\n\n"
    return body


def test_parse_events_skips_comments_and_joins_data_lines():
    lines = [": hello", "event: a", "data: 1", "data: 2", "", "", "data: x", ""]
    assert list(parse_events(iter(lines))) == [("a", "1\n2"), ("message", "x")]


def test_commands_are_yielded_and_other_events_ignored_then_it_reconnects():
    start = {"action": "start", "set_id": "s1", "device_id": 3}
    calls = []

    def handler(request: httpx.Request) -> httpx.Response:
        calls.append(request.headers["authorization"])
        if len(calls) == 1:
            return httpx.Response(503, text="busy")  # the first try fails: the stream retries
        return httpx.Response(200, text=_sse(("live.agent", {"data": {}}), ("live.command", {"data": start}),
                                             ("live.command", {"data": {"action": "dance"}})))  # fmt: skip

    stream = CommandStream("http://coach.test", "khd_x", log=lambda _: None, transport=httpx.MockTransport(handler),
                           seed=1)  # fmt: skip
    stop = threading.Event()
    got = next(stream.commands(stop))
    assert got == start and calls == ["Bearer khd_x", "Bearer khd_x"]


def test_publisher_sends_the_newest_message_and_keeps_the_end_of_a_set():
    sent, gate = [], threading.Event()

    def handler(request: httpx.Request) -> httpx.Response:
        gate.wait(5)  # a slow network: messages pile up meanwhile
        sent.append(json.loads(request.content))
        return httpx.Response(204)

    pub = Publisher("http://coach.test", "khd_x", log=lambda _: None, transport=httpx.MockTransport(handler))
    t0 = time.monotonic()
    for i in range(50):
        pub.offer({"count": i})
    pub.offer({"state": "ended"}, keep=True)
    assert time.monotonic() - t0 < 1.0  # offering never waits for the network
    gate.set()
    pub.close()
    counts = [m.get("count") for m in sent]
    assert sent[-1] == {"count": 49} or {"state": "ended"} in sent
    assert {"state": "ended"} in sent and len(sent) <= 4, counts  # old progress dropped, the end kept


def test_publisher_drops_messages_when_the_server_is_down():
    def handler(request: httpx.Request) -> httpx.Response:
        raise httpx.ConnectError("down")

    logged: list[str] = []
    pub = Publisher("http://coach.test", "khd_x", log=logged.append, transport=httpx.MockTransport(handler))
    pub.offer({"count": 1})
    pub.offer({"state": "ended"}, keep=True)
    pub.close()
    assert pub.sent == 0 and pub.dropped >= 1 and len(logged) == 1  # logged once per outage, not per message
