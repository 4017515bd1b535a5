"""An event stream open when its login ends (logout) ends at once, instead of delivering events for the rest of its
lifetime (COACH_EVENTS_STREAM_MAX_S, 300 s) to whoever holds the cookie; its reconnection is refused."""

from __future__ import annotations

import threading
import time

import httpx

from tests.frontend.conftest import PATIENT, api_client


def test_logout_ends_the_logins_open_event_stream(live_server):
    rose, rose_headers = api_client(live_server.url, PATIENT)
    cookie = {"coach_session": rose.cookies["coach_session"]}
    lines: list[str] = []
    ended = threading.Event()

    def listen() -> None:
        with httpx.stream("GET", f"{live_server.url}/api/v1/events", cookies=cookie, timeout=60) as stream:
            for line in stream.iter_lines():
                lines.append(line)
        ended.set()

    listener = threading.Thread(target=listen, daemon=True)
    listener.start()
    deadline = time.monotonic() + 10
    while ": connected" not in lines and time.monotonic() < deadline:
        time.sleep(0.05)
    assert ": connected" in lines, lines
    try:
        assert rose.post("/api/v1/auth/logout", headers=rose_headers).status_code == 204
    finally:
        rose.close()
    assert ended.wait(10), "the stream of a login that ended is still open"
    assert not [line for line in lines if line.startswith("data:")], lines
    assert httpx.get(f"{live_server.url}/api/v1/events", cookies=cookie, timeout=10).status_code == 401
