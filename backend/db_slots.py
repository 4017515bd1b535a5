"""Admission to the database: at most as many requests do their database part at once as the pool has connections.

Why. A sync route and its sync dependencies run in worker threads (anyio: 40 per process), each taking its turn for
a thread, and the request's session holds a pooled connection from its first query to its commit. With more
requests in flight than threads plus connections, every thread can end up waiting for a connection while every
connection belongs to a request that waits for a thread: nothing moves until the pool's 30 s timeout answers 500
(bench/README.md, "A crowd of simultaneous requests").

How. Every HTTP request except the static files waits here (in the event loop, holding neither a thread nor a
connection) for one of `capacity` slots, the pool's size plus its overflow, and gives the slot back when its
response starts (the database part is over then: the request's session commits before the answer is sent;
DbSession is a function-scoped dependency) or when it ends without one. A request that cannot get a slot within
wait_s is answered 503 ServerBusy with Retry-After. A stream that uses the database later, while it is open (the
home agent's heartbeat), takes a slot for each such step (DbSlots.held). A route that waits on the network with no
database work gives its slot back meanwhile (lease_of(request).paused(): a session upload while its body comes in
over a patient's slow uplink, after committing its login check). Pools without a fixed size (SQLite in memory,
NullPool) get no limit.
"""

from __future__ import annotations

import asyncio
import json
import weakref
from collections.abc import AsyncIterator, Callable
from contextlib import asynccontextmanager
from functools import cached_property

from sqlalchemy.engine import Engine
from sqlalchemy.pool import QueuePool
from starlette.requests import Request
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from backend.exceptions import ServerBusy

EXEMPT_PREFIXES = ("/static/",)  # files from disk: no database
SCOPE_KEY = "coach.db_lease"


def pool_capacity(engine: Engine) -> int | None:
    """Returns the most connections the engine's pool hands out at once (size + overflow), None when unbounded."""
    pool = engine.pool
    if isinstance(pool, QueuePool):
        return pool.size() + max(0, pool._max_overflow)  # noqa: SLF001 - QueuePool exposes no getter for it
    return None


class DbSlots:
    """The slots of one process. capacity is read from the engine on first use (the engine is made lazily)."""

    def __init__(self, engine: Callable[[], Engine], wait_s: float):
        self._engine = engine
        self.wait_s = wait_s
        self._per_loop: weakref.WeakKeyDictionary[asyncio.AbstractEventLoop, asyncio.Semaphore] = (
            weakref.WeakKeyDictionary()
        )

    @cached_property
    def capacity(self) -> int | None:
        """Returns the number of slots (None: no limit)."""
        return pool_capacity(self._engine())

    def _semaphore(self) -> asyncio.Semaphore | None:
        if self.capacity is None:
            return None
        loop = asyncio.get_running_loop()  # a semaphore belongs to one loop (tests start several)
        sem = self._per_loop.get(loop)
        if sem is None:
            sem = self._per_loop[loop] = asyncio.Semaphore(self.capacity)
        return sem

    async def acquire(self) -> Callable[[], None]:
        """Waits for a slot; returns the function that gives it back (call it once: SlotLease and held() do).
        Raises ServerBusy."""
        sem = self._semaphore()
        if sem is None:
            return lambda: None
        try:
            await asyncio.wait_for(sem.acquire(), timeout=self.wait_s)
        except TimeoutError:
            detail = f"no database connection came free within {self.wait_s:g} s; retry in a few seconds"
            raise ServerBusy(detail) from None
        return sem.release

    @asynccontextmanager
    async def held(self) -> AsyncIterator[None]:
        """Holds a slot for one database step of a stream (async with slots.held(): ...)."""
        release = await self.acquire()
        try:
            yield
        finally:
            release()


class SlotLease:
    """One request's slot: taken before the app runs, given back when the response starts. slots None: a lease that
    holds nothing (an app without DbAdmission)."""

    def __init__(self, slots: DbSlots | None):
        self._slots = slots
        self._release: Callable[[], None] | None = None

    async def acquire(self) -> None:
        """Takes the slot (waits; raises ServerBusy)."""
        if self._slots is not None and self._release is None:
            self._release = await self._slots.acquire()

    def release(self) -> None:
        """Gives the slot back (nothing when not held)."""
        release, self._release = self._release, None
        if release is not None:
            release()

    @asynccontextmanager
    async def paused(self) -> AsyncIterator[None]:
        """Gives the slot back for the block (network waits, no database work: commit first) and takes it again."""
        self.release()
        try:
            yield
        finally:
            await self.acquire()


def lease_of(request: Request) -> SlotLease:
    """Returns the request's slot lease (a lease that does nothing when the app runs without DbAdmission)."""
    return request.scope.get(SCOPE_KEY) or SlotLease(None)


class DbAdmission:
    """ASGI middleware: each HTTP request (but the static files) holds a DbSlots slot until its response starts."""

    def __init__(self, app: ASGIApp, slots: DbSlots):
        self.app = app
        self.slots = slots

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http" or scope["path"].startswith(EXEMPT_PREFIXES):
            await self.app(scope, receive, send)
            return
        lease = SlotLease(self.slots)
        try:
            await lease.acquire()
        except ServerBusy as exc:
            await _busy(send, exc.message)
            return
        scope[SCOPE_KEY] = lease

        async def send_releasing(message: Message) -> None:
            if message["type"] == "http.response.start":
                lease.release()
            await send(message)

        try:
            await self.app(scope, receive, send_releasing)
        finally:
            lease.release()


async def _busy(send: Send, detail: str) -> None:
    body = json.dumps({"error": "ServerBusy", "detail": detail}).encode()
    headers = [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode()),
               (b"retry-after", b"5")]  # fmt: skip
    await send({"type": "http.response.start", "status": 503, "headers": headers})
    await send({"type": "http.response.body", "body": body})
