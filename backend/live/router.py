"""The live loop's routes: the agent's command stream and progress, and the patient's Start and Stop."""

from __future__ import annotations

import asyncio
import time
from collections.abc import AsyncIterator, Callable
from typing import Annotated, Any, TypeVar

import anyio
from fastapi import APIRouter, Query, Request, status
from fastapi.responses import StreamingResponse
from sqlalchemy.orm import Session
from starlette.concurrency import run_in_threadpool

from backend.audit.service import record
from backend.config import Settings
from backend.deps import Caller, CurrentCaller, CurrentDevice, DbSession, UserCaller, require_patient_access
from backend.events.hub import HUB, RETRY_MS, SERVER_STOPPING, Event, Subscriber, publish
from backend.exceptions import (
    AUTH_ERRORS,
    AgentOffline,
    Forbidden,
    LiveSetUnknown,
    PatientNotFound,
    PlanNotFound,
    error_responses,
)
from backend.live import service
from backend.live.progress_gate import LiveProgressTooFast
from backend.live.schemas import AgentStatusOut, LiveSetOut, ProgressIn, StartIn, StopIn
from backend.schemas import IdQuery

router = APIRouter(prefix="/api/v1/live", tags=["live"])
T = TypeVar("T")
POLL_S = 1.0  # how often the agent's stream checks that the agent is still there


def _committed(fn: Callable[..., T], db_session: Session, **kwargs: Any) -> T:
    """Runs a service function and commits (events go out at the commit); returns its result."""
    result = fn(db_session=db_session, **kwargs)
    db_session.commit()
    return result


@router.get(
    "/agent",
    response_class=StreamingResponse,
    responses={
        200: {
            "content": {"text/event-stream": {}},
            "description": "events live.command: data {kind, patient_id, "
            "data: {action start|stop, set_id, device_id, exercise_slug, target_reps, angles}}",
        },  # fmt: skip
        **error_responses(*AUTH_ERRORS),
    },
)
async def agent_stream(request: Request, device: CurrentDevice, db_session: DbSession) -> StreamingResponse:
    """Streams the commands for the calling home agent; the device counts as online while the stream is open."""
    stream_id = await run_in_threadpool(_committed, service.connect, db_session, device=device)
    subscriber = HUB.subscribe(frozenset({device.patient_id}), frozenset({"live.command"}))
    return StreamingResponse(
        _agent_events(request, subscriber, db_session, device.id, stream_id, request.app.state.settings),
        media_type="text/event-stream",
        headers={"Cache-Control": "no-store", "X-Accel-Buffering": "no"},
    )


async def _agent_events(
    request: Request,
    subscriber: Subscriber,
    db_session: Session,
    device_id: int,
    stream_id: str,
    settings: Settings,
) -> AsyncIterator[str]:
    """Yields the device's commands and keep-alives until it leaves, is revoked or replaced, or EVENTS_STREAM_MAX_S
    pass.

    When it ends, the device is announced offline after LIVE_OFFLINE_GRACE_S unless a new stream of it began
    meanwhile (an agent reconnecting after the stream's lifetime, or after a network blip, never shows offline)."""
    slots = request.app.state.db_slots
    now = time.monotonic()
    deadline, beat = now + settings.EVENTS_STREAM_MAX_S, now + service.HEARTBEAT_S
    try:
        yield f"retry: {RETRY_MS}\n: connected\n\n"
        while time.monotonic() < deadline and not await request.is_disconnected():
            if time.monotonic() >= beat:
                async with slots.held():  # the stream's response has started: it holds no slot of its own
                    alive = await run_in_threadpool(_committed, service.heartbeat, db_session, device_id=device_id,
                                                    stream_id=stream_id)  # fmt: skip
                if not alive:
                    break
                beat += service.HEARTBEAT_S
                yield ": keep-alive\n\n"
            try:
                ev = await asyncio.wait_for(subscriber.queue.get(), timeout=POLL_S)
            except TimeoutError:
                continue
            if ev.kind == SERVER_STOPPING:
                break
            if ev.data.get("device_id") in (device_id, None):  # None: any device of the patient
                yield f"event: {ev.kind}\ndata: {ev.to_json()}\n\n"
    finally:
        HUB.unsubscribe(subscriber)
        with anyio.CancelScope(shield=True):
            if not HUB.stopping:  # a stopping server does not wait for a reconnection
                await anyio.sleep(settings.LIVE_OFFLINE_GRACE_S)
            async with slots.held():
                await run_in_threadpool(_committed, service.disconnect, db_session, device_id=device_id,
                                        stream_id=stream_id)  # fmt: skip


@router.post(
    "/progress",
    status_code=status.HTTP_204_NO_CONTENT,
    responses=error_responses(*AUTH_ERRORS, LiveSetUnknown, LiveProgressTooFast),
)
def post_progress(body: ProgressIn, request: Request, device: CurrentDevice, db_session: DbSession) -> None:
    """Passes one live message of the calling agent to its patient's pages (nothing is stored); a message repeating
    the device's last one is not passed on, and "recording" messages are limited (progress_gate.py: 429). Only the
    set the server last started on this device is accepted (409 LiveSetUnknown otherwise)."""
    service.require_started_set(device, body.set_id)
    message = body.model_dump()
    if request.app.state.live_progress.admit(device.id, message):
        publish(db_session, Event("live.progress", device.patient_id, message | {"device_id": device.id}))


def _patient_of(caller: Caller, patient_id: int | None) -> int:
    if patient_id is not None:
        return patient_id
    if caller.device is not None:
        return caller.device.patient_id
    if caller.user is not None and caller.user.role == "patient":
        return caller.user.id
    raise PatientNotFound("give patient_id: only patients and devices have a patient of their own")


@router.get("/status", response_model=AgentStatusOut, responses=error_responses(*AUTH_ERRORS, PatientNotFound))
def get_status(
    caller: CurrentCaller,
    db_session: DbSession,
    patient_id: Annotated[IdQuery, Query(description="the patient (default: the caller's own)")] = None,
) -> AgentStatusOut:
    """Returns whether the patient's home agent is connected now."""
    pid = _patient_of(caller, patient_id)
    require_patient_access(pid, caller=caller, db_session=db_session)
    return service.agent_status(db_session=db_session, patient_id=pid)


def _the_patient(caller: Caller) -> int:
    if caller.user is None or caller.user.role != "patient":
        raise Forbidden("only patients start and stop their own sets, from their page")
    return caller.user.id


@router.post(
    "/start",
    response_model=LiveSetOut,
    status_code=status.HTTP_202_ACCEPTED,
    responses=error_responses(*AUTH_ERRORS, PlanNotFound, AgentOffline),
)
def start(body: StartIn, caller: UserCaller, db_session: DbSession) -> LiveSetOut:
    """Asks the calling patient's home agent to record one set of an exercise of their plan."""
    out = service.start_set(db_session=db_session, patient_id=_the_patient(caller), plan_item_id=body.plan_item_id)
    record(db_session=db_session, caller=caller, action="live.start", object_type="live_set", object_id=out.set_id,
           patient_id=out.patient_id, detail={"exercise": out.exercise_slug, "device_id": out.device_id})  # fmt: skip
    return out


@router.post(
    "/stop",
    response_model=LiveSetOut,
    status_code=status.HTTP_202_ACCEPTED,
    responses=error_responses(*AUTH_ERRORS),
)
def stop(body: StopIn, caller: UserCaller, db_session: DbSession) -> LiveSetOut:
    """Asks the calling patient's home agent to end the set (what it recorded is kept); a set that is not running
    is left as it is."""
    out = service.stop_set(db_session=db_session, patient_id=_the_patient(caller), set_id=body.set_id)
    record(db_session=db_session, caller=caller, action="live.stop", object_type="live_set", object_id=out.set_id,
           patient_id=out.patient_id)  # fmt: skip
    return out
