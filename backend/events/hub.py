"""Events the pages and home agents listen to, from any worker or replica: stored data changed (a new session,
changed advice, a changed plan) and the live loop (an agent connected or left, a command to it, its progress).

publish() attaches an event to the database transaction that makes the change, so an event goes out only for data
that is committed, and only once:
- PostgreSQL (production, several workers and replicas): `pg_notify` inside the transaction; PostgreSQL delivers
  it at commit to every process LISTENing on CHANNEL (listener.py), each of which hands it to its own HUB.
- SQLite (the embedded demo, one process): straight to this process's HUB after the commit.
HUB fans events out to the server-sent-event streams of this process (events/router.py, live/router.py), each
filtered by kind and by the patients its caller may see.
"""

from __future__ import annotations

import asyncio
import json
import threading
from dataclasses import asdict, dataclass, field
from typing import Any

from sqlalchemy import event, select
from sqlalchemy import func as sa_func
from sqlalchemy.orm import Session

from backend.exceptions import AppError

CHANNEL = "coach_events"
_PENDING = "coach_events"  # key in Session.info: events waiting for the commit
DATA_KINDS = ("session.stored", "suggestion.changed", "plan.changed", "reply.changed")  # stored data changed
LIVE_KINDS = ("live.agent", "live.command", "live.progress")  # a home agent's presence, its commands, its progress
KINDS = DATA_KINDS + LIVE_KINDS
# a login (login_session_id), API tokens (api_token_ids), a device (device_id) or every login and token of a user
# (user_id; also the devices of a patient who is deactivated) ended: its open streams end too, and their reconnection
# checks the credential again; patient_id 0 (it is about a caller, not a patient)
ACCESS_ENDED = "access.ended"
# the server is stopping (Ctrl-C, SIGTERM): every open stream ends at once, so the stop waits for none of them
SERVER_STOPPING = "server.stopping"
RETRY_MS = (
    3000  # every event stream (backend.events.router, backend.live.router): how long the browser waits to reconnect
)


@dataclass(frozen=True)
class Event:
    """Something changed about one patient: `kind` (one of KINDS), the patient, and ids the page may use."""

    kind: str
    patient_id: int
    data: dict[str, Any] = field(default_factory=dict[str, Any])

    def to_json(self) -> str:
        """Returns the event as compact JSON."""
        return json.dumps(asdict(self), separators=(",", ":"))

    @classmethod
    def from_json(cls, text: str) -> Event:
        """Returns the event of a JSON text written by to_json; raises ValueError when it is not one."""
        raw = json.loads(text)
        kind_ok = raw.get("kind") in (*KINDS, ACCESS_ENDED) if isinstance(raw, dict) else False
        if not kind_ok or not isinstance(raw.get("patient_id"), int):
            raise ValueError(f"not an event: {text[:200]!r}")
        return cls(kind=raw["kind"], patient_id=raw["patient_id"], data=dict(raw.get("data") or {}))


class Subscriber:
    """One event stream: events of some kinds about some patients (None = all), queued for an asyncio consumer;
    user_id, login_id, token_id, device_id: the credential it was opened with (ACCESS_ENDED events for them end it);
    a device's stream has the device's patient as user_id (a deactivated patient's devices stop too)."""

    def __init__(
        self,
        patient_ids: frozenset[int] | None,
        kinds: frozenset[str] = frozenset(KINDS),
        maxsize: int = 100,
        user_id: int | None = None,
        login_id: int | None = None,
        token_id: int | None = None,
        device_id: int | None = None,
    ) -> None:
        self.patient_ids = patient_ids
        self.kinds = kinds
        self.user_id = user_id
        self.login_id = login_id
        self.token_id = token_id
        self.device_id = device_id
        self.loop = asyncio.get_running_loop()
        self.queue: asyncio.Queue[Event] = asyncio.Queue(maxsize=maxsize)

    def wants(self, ev: Event) -> bool:
        """Returns whether this stream shows ev (its kind, about one of its patients), or ends with it (its login)."""
        if ev.kind == SERVER_STOPPING:
            return True
        if ev.kind == ACCESS_ENDED:
            login, user, device = ev.data.get("login_session_id"), ev.data.get("user_id"), ev.data.get("device_id")
            tokens = ev.data.get("api_token_ids") or ()
            return (
                (login is not None and login == self.login_id)
                or (user is not None and user == self.user_id)
                or (device is not None and device == self.device_id)
                or (self.token_id is not None and self.token_id in tokens)
            )
        return ev.kind in self.kinds and (self.patient_ids is None or ev.patient_id in self.patient_ids)

    def offer(self, ev: Event) -> None:
        """Queues ev (called on the subscriber's event loop); a full queue drops it (the page reloads anyway)."""
        if not self.queue.full():
            self.queue.put_nowait(ev)


RETRY_MS = 3000  # how long a page's stream waits before reconnecting (both streams' "retry:" line)
MAX_STREAMS_PER_USER = 50  # open event streams of one user per server process (a closed page may linger 15 s)


class TooManyStreams(AppError):
    """The caller already has MAX_STREAMS_PER_USER event streams open on this server process."""

    status_code = 429


class Hub:
    """This process's fan-out of events to its subscribers; deliver() may be called from any thread."""

    def __init__(self) -> None:
        self._subscribers: set[Subscriber] = set()
        self._lock = threading.Lock()
        self.stopping = False  # set by stop_all(): streams end without their usual grace periods

    def subscribe(
        self,
        patient_ids: frozenset[int] | None,
        kinds: frozenset[str] = frozenset(KINDS),
        user_id: int | None = None,
        login_id: int | None = None,
        token_id: int | None = None,
        device_id: int | None = None,
    ) -> Subscriber:
        """Returns a new subscriber (call on the event loop that will read it); raises TooManyStreams when user_id
        already has MAX_STREAMS_PER_USER open here."""
        sub = Subscriber(patient_ids, kinds, user_id=user_id, login_id=login_id, token_id=token_id, device_id=device_id)
        with self._lock:
            if user_id is not None and sum(s.user_id == user_id for s in self._subscribers) >= MAX_STREAMS_PER_USER:
                raise TooManyStreams(f"at most {MAX_STREAMS_PER_USER} event streams may be open at once per user",
                                     headers={"Retry-After": "5"})  # fmt: skip
            self._subscribers.add(sub)
        return sub

    def unsubscribe(self, sub: Subscriber) -> None:
        """Forgets a subscriber."""
        with self._lock:
            self._subscribers.discard(sub)

    def deliver(self, ev: Event) -> int:
        """Hands ev to every subscriber that wants it; returns how many."""
        with self._lock:
            targets = [s for s in self._subscribers if s.wants(ev)]
        for sub in targets:
            try:
                sub.loop.call_soon_threadsafe(sub.offer, ev)
            except RuntimeError:  # its loop is closed: the stream ended
                self.unsubscribe(sub)
        return len(targets)

    def stop_all(self) -> int:
        """Ends every open stream of this process (the server is stopping); returns how many there were."""
        self.stopping = True
        return self.deliver(Event(SERVER_STOPPING, 0, {}))

    def count(self) -> int:
        """Returns the number of subscribers."""
        with self._lock:
            return len(self._subscribers)


HUB = Hub()


def publish(db_session: Session, ev: Event) -> None:
    """Sends ev when db_session's transaction commits (never when it rolls back)."""
    db_session.info.setdefault(_PENDING, []).append(ev)


def pending(db_session: Session) -> list[Event]:
    """Returns the events waiting for db_session's commit (in the order published)."""
    return list(db_session.info.get(_PENDING, []))


@event.listens_for(Session, "before_commit")
def _notify_in_transaction(db_session: Session) -> None:
    events = db_session.info.get(_PENDING)
    if not events or db_session.get_bind().dialect.name != "postgresql":
        return
    db_session.info[_PENDING] = []
    for ev in events:
        db_session.execute(select(sa_func.pg_notify(CHANNEL, ev.to_json())))


@event.listens_for(Session, "after_commit")
def _deliver_in_process(db_session: Session) -> None:
    events = db_session.info.pop(_PENDING, None)  # left only on databases without NOTIFY (SQLite)
    for ev in events or ():
        HUB.deliver(ev)


@event.listens_for(Session, "after_rollback")
def _forget(db_session: Session) -> None:
    db_session.info.pop(_PENDING, None)
