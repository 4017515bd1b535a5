"""Presence of home agents and the commands sent to them (queries only; the router streams and publishes).

A device is online while it holds its command stream: connect() records the stream's id, heartbeat() refreshes
last_seen_at every HEARTBEAT_S, disconnect() clears the id unless a newer stream replaced it. A worker that dies
without disconnecting leaves a stale id, so "online" also needs last_seen_at within STALE_S.
"""

from __future__ import annotations

import datetime as dt
import uuid

from sqlalchemy import select
from sqlalchemy.orm import Session

from backend.database import utcnow
from backend.devices.models import Device
from backend.events.hub import Event, publish
from backend.exceptions import AgentOffline, LiveSetUnknown
from backend.i18n import N_
from backend.live.schemas import AgentStatusOut, LiveSetOut
from backend.plans.service import patient_plan_item
from backend.users.models import User

HEARTBEAT_S = 15.0
STALE_S = 3 * HEARTBEAT_S


def _agent_event(device: Device, online: bool) -> Event:
    return Event("live.agent", device.patient_id, {"device_id": device.id, "online": online})


def connect(*, db_session: Session, device: Device) -> str:
    """Makes a new command stream the device's current one; returns its id and announces the device online."""
    stream_id = str(uuid.uuid4())
    device.live_stream_id = stream_id
    device.last_seen_at = utcnow()
    publish(db_session, _agent_event(device, True))
    db_session.flush()
    return stream_id


def heartbeat(*, db_session: Session, device_id: int, stream_id: str) -> bool:
    """Refreshes the device's last_seen_at; returns False when the stream should end (revoked, replaced, or its
    patient deactivated)."""
    device = db_session.get(Device, device_id, populate_existing=True)
    if device is None or device.revoked_at is not None or device.live_stream_id != stream_id:
        return False
    patient = db_session.get(User, device.patient_id, populate_existing=True)
    if patient is None or not patient.is_active:
        return False
    device.last_seen_at = utcnow()
    db_session.flush()
    return True


def disconnect(*, db_session: Session, device_id: int, stream_id: str) -> bool:
    """Announces the device offline when stream_id is still its current stream; returns whether it was."""
    device = db_session.get(Device, device_id, populate_existing=True)
    if device is None or device.live_stream_id != stream_id:
        return False
    device.live_stream_id = None
    publish(db_session, _agent_event(device, False))
    db_session.flush()
    return True


def online_device(*, db_session: Session, patient_id: int, now: dt.datetime | None = None) -> Device | None:
    """Returns the patient's connected device (the one heard from last), or None."""
    fresh = (now or utcnow()) - dt.timedelta(seconds=STALE_S)
    query = (
        select(Device)
        .where(Device.patient_id == patient_id, Device.revoked_at.is_(None), Device.live_stream_id.is_not(None))
        .where(Device.last_seen_at >= fresh)
        .order_by(Device.last_seen_at.desc(), Device.id.desc())
        .limit(1)
    )
    return db_session.scalar(query)


def agent_status(*, db_session: Session, patient_id: int) -> AgentStatusOut:
    """Returns whether the patient's home agent is connected, and which device it is."""
    device = online_device(db_session=db_session, patient_id=patient_id)
    if device is not None:
        return AgentStatusOut(patient_id=patient_id, state="online", device_id=device.id, device_name=device.name,
                              last_seen_at=device.last_seen_at)  # fmt: skip
    paired = db_session.scalar(
        select(Device)
        .where(Device.patient_id == patient_id, Device.revoked_at.is_(None))
        .order_by(Device.last_seen_at.desc().nulls_last(), Device.id.desc())
        .limit(1)
    )
    if paired is None:
        return AgentStatusOut(patient_id=patient_id, state="unpaired")
    return AgentStatusOut(patient_id=patient_id, state="offline", device_id=paired.id, device_name=paired.name,
                          last_seen_at=paired.last_seen_at)  # fmt: skip


def _require_online(db_session: Session, patient_id: int) -> Device:
    device = online_device(db_session=db_session, patient_id=patient_id)
    if device is None:
        raise AgentOffline(N_("your home computer is not connected: check that it is switched on and online"))
    return device


def start_set(*, db_session: Session, patient_id: int, plan_item_id: int) -> LiveSetOut:
    """Asks the patient's connected agent to record one set of a plan item; raises PlanNotFound or AgentOffline."""
    item, exercise = patient_plan_item(db_session=db_session, patient_id=patient_id, plan_item_id=plan_item_id)
    device = _require_online(db_session, patient_id)
    out = LiveSetOut(set_id=str(uuid.uuid4()), patient_id=patient_id, device_id=device.id,
                     exercise_slug=exercise.slug, target_reps=item.repetitions, action="start")  # fmt: skip
    device.live_set_id = out.set_id  # the only set whose progress this device may post (require_started_set)
    db_session.flush()
    data = out.model_dump() | {"angles": list(exercise.defining_angles), "plan_item_id": item.id}
    publish(db_session, Event("live.command", patient_id, data))
    return out


def require_started_set(device: Device, set_id: str) -> None:
    """Raises LiveSetUnknown unless set_id is the set the server last started on this device (start_set stores it in
    the database, so every server worker agrees); progress for any other set would show a set that never began."""
    if device.live_set_id is None or device.live_set_id != set_id:
        raise LiveSetUnknown(f"set_id {set_id}: the server did not start this set on device {device.id}; live progress "
                             "is accepted only for the set the patient last started on this device")  # fmt: skip


def stop_set(*, db_session: Session, patient_id: int, set_id: str) -> LiveSetOut:
    """Asks the patient's agents to end the set set_id (the one recording it stores what was recorded)."""
    out = LiveSetOut(set_id=set_id, patient_id=patient_id, device_id=None, exercise_slug="", target_reps=None,
                     action="stop")  # fmt: skip
    publish(db_session, Event("live.command", patient_id, out.model_dump()))
    return out
