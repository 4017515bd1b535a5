"""GET /api/v1/events: server-sent events about the patients the caller may see, so pages update by themselves."""

from __future__ import annotations

import asyncio
import time
from collections.abc import AsyncIterator
from dataclasses import dataclass
from typing import Annotated

from fastapi import APIRouter, Query, Request
from fastapi.responses import StreamingResponse
from sqlalchemy import select
from sqlalchemy.orm import Session
from starlette.concurrency import run_in_threadpool

from backend.deps import Caller, DbSession, current_caller, optional_caller, require_patient_access
from backend.events.hub import (
    ACCESS_ENDED,
    DATA_KINDS,
    HUB,
    KINDS,
    RETRY_MS,
    SERVER_STOPPING,
    Subscriber,
    TooManyStreams,
)
from backend.exceptions import AUTH_ERRORS, PatientNotFound, error_responses
from backend.patients.models import TherapistPatient
from backend.schemas import IdQuery

router = APIRouter(prefix="/api/v1", tags=["events"])
KEEPALIVE_S = 15.0  # a comment line this often keeps proxies from closing an idle stream
PING_S = 2.0  # live streams: an event this often, so a page notices a silently lost connection within seconds


def visible_patients(caller: Caller, db_session: Session, patient_id: int | None) -> frozenset[int] | None:
    """Returns the patient ids whose events the caller may receive (None = every patient: admins)."""
    if patient_id is not None:
        require_patient_access(patient_id, caller=caller, db_session=db_session)
        return frozenset({patient_id})
    if caller.device is not None:
        return frozenset({caller.device.patient_id})
    user = caller.signed_in_user
    if user.role == "patient":
        return frozenset({user.id})
    if user.role == "therapist":
        assigned = select(TherapistPatient.patient_id).where(TherapistPatient.therapist_id == user.id)
        return frozenset(db_session.scalars(assigned))
    return None


@router.get(
    "/events",
    response_class=StreamingResponse,
    responses={
        200: {
            "content": {"text/event-stream": {}},
            "description": "events: session.stored, suggestion.changed, plan.changed, reply.changed "
            "(and with live=true live.agent, live.command, live.progress); data: {kind, patient_id, data}",
        },  # fmt: skip
        **error_responses(*AUTH_ERRORS, PatientNotFound, TooManyStreams),
    },
)
async def stream_events(
    request: Request,
    db_session: DbSession,
    patient_id: Annotated[IdQuery, Query(description="only this patient's events")] = None,
    live: Annotated[bool, Query(description="also the live loop's events (home agent, progress)")] = False,
) -> StreamingResponse:
    """Streams server-sent events about the patients the caller may see (one patient with patient_id)."""
    patients, owner = await run_in_threadpool(_authorize, request, db_session, patient_id)
    subscriber = HUB.subscribe(patients, frozenset(KINDS if live else DATA_KINDS), **owner.__dict__)
    return StreamingResponse(
        _stream(request, subscriber, request.app.state.settings.EVENTS_STREAM_MAX_S, PING_S if live else None),
        media_type="text/event-stream",
        headers={"Cache-Control": "no-store", "X-Accel-Buffering": "no"},
    )


@dataclass(frozen=True)
class StreamOwner:
    """The credential a stream was opened with (Subscriber's keywords): its end (ACCESS_ENDED) ends the stream."""

    user_id: int | None
    login_id: int | None
    token_id: int | None
    device_id: int | None


def _authorize(
    request: Request, db_session: Session, patient_id: int | None
) -> tuple[frozenset[int] | None, StreamOwner]:
    """Returns (the patients whose events the caller may receive, its credential), checking the login, in one thread
    from the first query to the commit that gives the connection back. A reconnecting crowd of pages (every stream
    ends after EVENTS_STREAM_MAX_S) then never holds pooled connections while it waits for a thread, which had
    starved the pool with 200 pages open."""
    caller = current_caller(request, optional_caller(request, db_session))
    patients = visible_patients(caller, db_session, patient_id)
    owner = StreamOwner(
        user_id=caller.device.patient_id if caller.device is not None else caller.signed_in_user.id,
        login_id=caller.login_session.id if caller.login_session is not None else None,
        token_id=caller.api_token.id if caller.api_token is not None else None,
        device_id=caller.device.id if caller.device is not None else None,
    )
    db_session.commit()
    return patients, owner


async def _stream(
    request: Request, subscriber: Subscriber, max_s: float, ping_s: float | None = None
) -> AsyncIterator[str]:
    """Yields the stream's text: the retry delay, then events and keep-alive comments until the client leaves or
    max_s seconds pass (the browser then reconnects, and its login is checked again). With ping_s, the keep-alive
    is an event "ping" every ping_s seconds (scripts see events, not comments: the page's connection watchdog)."""
    deadline = time.monotonic() + max_s
    idle_s, keepalive = (ping_s, "event: ping\ndata: {}\n\n") if ping_s else (KEEPALIVE_S, ": keep-alive\n\n")
    try:
        yield f"retry: {RETRY_MS}\n: connected\n\n"
        while time.monotonic() < deadline and not await request.is_disconnected():
            try:
                left = deadline - time.monotonic()
                ev = await asyncio.wait_for(subscriber.queue.get(), timeout=max(0.0, min(idle_s, left)))
            except TimeoutError:
                yield keepalive
                continue
            if ev.kind in (ACCESS_ENDED, SERVER_STOPPING):  # the login ended (a reconnection is refused), or the server
                break
            yield f"event: {ev.kind}\ndata: {ev.to_json()}\n\n"
    finally:
        HUB.unsubscribe(subscriber)
