"""Uploading queued session files: POST /api/v1/sessions with the file as the body, idempotent and retried.

The server deduplicates on (patient, session id) + content hash, so sending a file twice (e.g. when the first
response was lost) stores it once and answers 200. Outcomes per file:
    200, 201                      -> "sent"      (the queue records the receipt, then drops the file)
    401                           -> "kept"      (device token refused: pair again; the file waits, never dropped)
    404/405 without a domain error -> "kept"     (no upload endpoint at that URL: a wrong URL is no bad file)
    other 4xx except 408 and 429  -> "rejected"  (moved to queue/rejected/ with the server's error)
    408, 429, 5xx, network errors -> retried with exponential backoff and full jitter, then "kept"
    the same server error (5xx but 502/503/504) in HOLD_AFTER_SERVER_ERRORS passes in a row -> "held" (set aside in
                                     queue/held/ with the server's answer, so that it no longer holds back the others)
"""

from __future__ import annotations

import random
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import httpx

from kinect_agent import __version__
from kinect_agent.queue import HOLD_AFTER_SERVER_ERRORS, SessionQueue

UPLOAD_PATH = "/api/v1/sessions"
RETRYABLE_4XX = frozenset({408, 429})
_NO_ROUTE = (None, "NotFound", "MethodNotAllowed")  # a 404/405 without a domain error: the route is missing
PASSING_5XX = frozenset({502, 503, 504})  # a proxy without its server, or a busy server: never this file's fault
DEFAULT_TIMEOUT = httpx.Timeout(60.0, connect=5.0)


@dataclass
class UploadResult:
    """What happened to one queued file: outcome "sent", "rejected", "held" (set aside after the same server error
    pass after pass), "kept" (still queued) or "gone" (not found)."""

    path: Path
    session_id: str
    outcome: str
    status_code: int | None = None  # last HTTP status; None after a network error
    detail: str = ""  # the server's error detail or the network error
    attempts: int = 0
    response: dict[str, Any] = field(default_factory=dict)  # the server's JSON body (SessionOut or an error)


@dataclass
class RetryPolicy:
    """Exponential backoff with full jitter: attempt k waits uniform(0, min(max_delay_s, base_delay_s * 2**k))."""

    max_attempts: int = 4
    base_delay_s: float = 0.5
    max_delay_s: float = 30.0

    def delay(self, attempt: int, rng: random.Random, retry_after: float | None = None) -> float:
        """Returns seconds to wait before retry number `attempt` (0-based); honours Retry-After up to the cap."""
        if retry_after is not None:
            return min(max(retry_after, 0.0), self.max_delay_s)
        return rng.uniform(0.0, min(self.max_delay_s, self.base_delay_s * 2.0**attempt))


def _retry_after(response: httpx.Response) -> float | None:
    try:
        return float(response.headers["Retry-After"])
    except (KeyError, ValueError):
        return None


def _json_or_text(response: httpx.Response) -> tuple[dict[str, Any], str]:
    """Returns (JSON body or {}, a one-line detail for humans)."""
    try:
        body = response.json()
    except ValueError:
        return {}, response.text[:500]
    if not isinstance(body, dict):
        return {"body": body}, str(body)[:500]
    detail = body.get("detail")
    if isinstance(detail, str):
        return body, f"{body.get('error', 'error')}: {detail}" if body.get("error") else detail
    return body, str(detail if detail is not None else body)[:500]


class Uploader:
    """Sends session files to one server with one device token (an httpx.Client; close() when done)."""

    def __init__(
        self,
        server_url: str,
        device_token: str,
        *,
        transport: httpx.BaseTransport | None = None,
        timeout: httpx.Timeout = DEFAULT_TIMEOUT,
        policy: RetryPolicy | None = None,
        sleep: Callable[[float], None] = time.sleep,
        rng: random.Random | None = None,
    ) -> None:
        self.policy = policy or RetryPolicy()
        self.sleep = sleep
        self.rng = rng or random.Random()
        self.client = httpx.Client(
            base_url=server_url.rstrip("/"),
            transport=transport,
            timeout=timeout,
            headers={"Authorization": f"Bearer {device_token}", "User-Agent": f"kinect-agent/{__version__}"},
        )

    def close(self) -> None:
        """Closes the HTTP connections."""
        self.client.close()

    def __enter__(self) -> Uploader:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def upload_file(self, path: str | Path) -> UploadResult:
        """Posts one session file, retrying transient failures; returns the outcome (never raises for HTTP)."""
        path = Path(path)
        result = UploadResult(path=path, session_id=path.stem, outcome="kept")
        try:
            data = path.read_bytes()
        except FileNotFoundError:
            result.outcome, result.detail = "gone", f"{path}: left the queue meanwhile (another uploader sent it)"
            return result
        for attempt in range(self.policy.max_attempts):
            result.attempts = attempt + 1
            retry_after = None
            try:
                response = self.client.post(
                    UPLOAD_PATH, content=data, headers={"Content-Type": "application/octet-stream"}
                )
            except httpx.TransportError as exc:
                result.status_code, result.detail = None, f"{type(exc).__name__}: {exc}"
            else:
                result.status_code = response.status_code
                result.response, result.detail = _json_or_text(response)
                if response.status_code in (200, 201):
                    result.outcome = "sent"
                    return result
                if response.status_code == 401:
                    return result  # kept: the token is wrong or revoked; retrying will not help
                if response.status_code in (404, 405) and result.response.get("error") in _NO_ROUTE:
                    return result  # kept: no upload endpoint at this URL (wrong URL or older server), not a bad file
                if 400 <= response.status_code < 500 and response.status_code not in RETRYABLE_4XX:
                    result.outcome = "rejected"
                    return result
                retry_after = _retry_after(response)
            if attempt + 1 < self.policy.max_attempts:
                self.sleep(self.policy.delay(attempt, self.rng, retry_after))
        return result


@dataclass
class DrainReport:
    """The results of one pass over the queue, and how many files it left pending."""

    results: list[UploadResult]
    remaining: int

    def count(self, outcome: str) -> int:
        """Returns how many files had this outcome."""
        return sum(r.outcome == outcome for r in self.results)


def _lasting(status_code: int | None) -> bool:
    """True for a server error that may be this file's own (a 500), not a server that is down or busy."""
    return status_code is not None and status_code >= 500 and status_code not in PASSING_5XX


def drain(queue: SessionQueue, uploader: Uploader, *, log: Callable[[str], None] | None = None) -> DrainReport:
    """Uploads pending files oldest first; stops at the first file that stays queued (server down, busy or auth),
    except after a lasting server error (a 500): that may be caused by this one file, which must not hold back the
    files behind it. A file that meets the same lasting error in HOLD_AFTER_SERVER_ERRORS passes in a row is held
    aside (queue/held/, with the server's answer).

    A file leaves pending/ only after the server confirmed it (receipt written first), refused it (4xx) or failed
    on it again and again (held).
    """
    results = []
    for path in queue.pending():
        result = uploader.upload_file(path)
        results.append(result)
        error = {"status_code": result.status_code, "detail": result.detail, "response": result.response}
        if result.outcome == "sent":
            queue.mark_sent(path, _receipt(result))
        elif result.outcome == "rejected":
            queue.mark_rejected(path, error)
        elif result.outcome == "kept" and result.status_code is not None and _lasting(result.status_code):
            passes = queue.note_server_error(path, result.status_code, result.detail)
            if passes >= HOLD_AFTER_SERVER_ERRORS:
                queue.mark_held(path, {**error, "passes": passes})
                result.outcome = "held"
        if log is not None:
            log(_describe(result))
        if result.outcome == "kept" and not _lasting(result.status_code):
            break  # server down, overloaded or refusing the token: the next files would fare the same
    return DrainReport(results=results, remaining=len(queue.pending()))


def _receipt(result: UploadResult) -> dict[str, Any]:
    body = result.response
    return {
        "status_code": result.status_code,
        "server_session_id": body.get("id"),
        "patient_id": body.get("patient_id"),
        "exercise_slug": body.get("exercise_slug"),
        "content_hash": body.get("content_hash"),
        "attempts": result.attempts,
    }


def _describe(result: UploadResult) -> str:
    name = result.path.name
    if result.outcome == "sent":
        what = "stored" if result.status_code == 201 else "already stored"
        return f"{name}: {what} on the server (HTTP {result.status_code}, session {result.response.get('id')})"
    if result.outcome == "rejected":
        return f"{name}: rejected by the server (HTTP {result.status_code}: {result.detail}); moved to rejected/"
    if result.outcome == "gone":
        return f"{name}: {result.detail}"
    if result.outcome == "held":
        return (
            f"{name}: the server failed on it in {HOLD_AFTER_SERVER_ERRORS} passes in a row (HTTP "
            f"{result.status_code}: {result.detail}); set aside in held/ (kinect-agent upload --retry-held)"
        )
    if result.status_code in (404, 405):
        return f"{name}: the server has no {UPLOAD_PATH} endpoint (HTTP {result.status_code}); file kept"
    if result.status_code == 401:
        return f"{name}: device token refused ({result.detail}); pair again with kinect-agent pair; file kept"
    where = f"HTTP {result.status_code}" if result.status_code is not None else "network error"
    return f"{name}: not sent after {result.attempts} attempts ({where}: {result.detail}); kept in the queue"
