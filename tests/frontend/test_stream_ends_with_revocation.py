"""An event stream opened with an API token or a device token ends within 2 s when that token or device is revoked,
instead of delivering the patient's events for the rest of its lifetime (COACH_EVENTS_STREAM_MAX_S, 300 s); its
reconnection is refused."""

from __future__ import annotations

import threading
import time

import httpx

from tests.frontend.conftest import PATIENT, api_client

LIMIT_S = 2.0


class _Listener:
    """Reads /api/v1/events with the given headers in a thread; `ended` is set when the server ends the stream."""

    def __init__(self, url: str, headers: dict[str, str]) -> None:
        self.lines: list[str] = []
        self.ended = threading.Event()
        self._thread = threading.Thread(target=self._listen, args=(url, headers), daemon=True)
        self._thread.start()
        deadline = time.monotonic() + 10
        while ": connected" not in self.lines and time.monotonic() < deadline:
            time.sleep(0.05)
        assert ": connected" in self.lines, self.lines

    def _listen(self, url: str, headers: dict[str, str]) -> None:
        with httpx.stream("GET", f"{url}/api/v1/events", headers=headers, timeout=60) as stream:
            for line in stream.iter_lines():
                self.lines.append(line)
        self.ended.set()


def _ends_within_limit(listener: _Listener, revoke) -> float:
    """Revokes, then returns how long the stream took to end (fails after 10 s)."""
    start = time.monotonic()
    revoke()
    assert listener.ended.wait(10), "the stream of a revoked credential is still open"
    return time.monotonic() - start


def test_revoking_an_api_token_ends_its_open_event_stream(live_server):
    rose, csrf = api_client(live_server.url, PATIENT)
    try:
        made = rose.post("/api/v1/tokens", json={"name": "stream test", "scopes": ["read"]}, headers=csrf)
        assert made.status_code == 201, made.text
        bearer = {"Authorization": f"Bearer {made.json()['token']}"}
        listener = _Listener(live_server.url, bearer)
        took = _ends_within_limit(
            listener, lambda: rose.delete(f"/api/v1/tokens/{made.json()['id']}", headers=csrf).raise_for_status()
        )
    finally:
        rose.close()
    assert took < LIMIT_S, f"the stream ended {took:.1f} s after the revocation"
    assert httpx.get(f"{live_server.url}/api/v1/events", headers=bearer, timeout=10).status_code == 401


def test_revoking_a_device_ends_its_open_event_stream(live_server):
    rose, csrf = api_client(live_server.url, PATIENT)
    try:
        me = rose.get("/api/v1/users/me").json()
        code = rose.post(f"/api/v1/patients/{me['id']}/pairing-codes", headers=csrf)
        assert code.status_code == 201, code.text
        paired = httpx.post(f"{live_server.url}/api/v1/devices/pair", json={"code": code.json()["code"]}, timeout=10)
        assert paired.status_code == 201, paired.text
        bearer = {"Authorization": f"Bearer {paired.json()['token']}"}
        listener = _Listener(live_server.url, bearer)
        device_id = paired.json()["device_id"]
        took = _ends_within_limit(
            listener, lambda: rose.delete(f"/api/v1/devices/{device_id}", headers=csrf).raise_for_status()
        )
    finally:
        rose.close()
    assert took < LIMIT_S, f"the stream ended {took:.1f} s after the revocation"
    assert httpx.get(f"{live_server.url}/api/v1/events", headers=bearer, timeout=10).status_code == 401
