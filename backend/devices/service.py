"""Pairing codes and device tokens."""

from __future__ import annotations

import datetime as dt

from sqlalchemy import func, select
from sqlalchemy.orm import Session

from backend.database import utcnow
from backend.devices.models import Device, PairingCode
from backend.events.hub import ACCESS_ENDED, Event, publish
from backend.exceptions import DeviceNotFound, PairingCodeInvalid
from backend.security import DEVICE_TOKEN_PREFIX, new_pairing_code, new_token, normalize_pairing_code, token_hash


def missing(device_id: int) -> DeviceNotFound:
    """Returns the error for a device that does not exist, or that the caller has no right to know of."""
    return DeviceNotFound(f"device {device_id} does not exist")


def create_pairing_code(
    *, db_session: Session, patient_id: int, created_by_id: int | None, minutes: float
) -> tuple[PairingCode, str]:
    """Creates a single-use pairing code for a patient, valid for `minutes`; returns (row, code)."""
    code = new_pairing_code()
    now = utcnow()
    row = PairingCode(
        patient_id=patient_id,
        created_by_id=created_by_id,
        code_hash=token_hash(code),
        created_at=now,
        expires_at=now + dt.timedelta(minutes=minutes),
    )
    db_session.add(row)
    db_session.flush()
    return row, code


def pair(*, db_session: Session, code: str, name: str) -> tuple[Device, str]:
    """Uses a pairing code once and returns (new device, device token); raises PairingCodeInvalid."""
    row = db_session.scalar(
        select(PairingCode).where(PairingCode.code_hash == token_hash(normalize_pairing_code(code))).with_for_update()
    )
    now = utcnow()
    if row is None or row.used_at is not None or row.expires_at <= now:
        raise PairingCodeInvalid("pairing code is unknown, already used or expired; create a new one")
    token = new_token(DEVICE_TOKEN_PREFIX)
    device = Device(patient_id=row.patient_id, name=name, token_hash=token_hash(token), created_at=now)
    db_session.add(device)
    db_session.flush()
    row.used_at = now
    row.device_id = device.id
    db_session.flush()
    return device, token


def list_devices(*, db_session: Session, patient_id: int, limit: int, offset: int) -> tuple[list[Device], int]:
    """Returns one page of a patient's devices (by id) and the total."""
    query = select(Device).where(Device.patient_id == patient_id)
    total = db_session.scalar(select(func.count()).select_from(query.subquery())) or 0
    return list(db_session.scalars(query.order_by(Device.id).limit(limit).offset(offset))), total


def get_device(*, db_session: Session, device_id: int) -> Device:
    """Returns one device or raises DeviceNotFound."""
    device = db_session.get(Device, device_id)
    if device is None:
        raise missing(device_id)
    return device


def revoke(*, db_session: Session, device: Device) -> Device:
    """Revokes a device token (idempotent) and ends its open event streams."""
    if device.revoked_at is None:
        device.revoked_at = utcnow()
    publish(db_session, Event(ACCESS_ENDED, 0, {"device_id": device.id}))
    db_session.flush()
    return device
