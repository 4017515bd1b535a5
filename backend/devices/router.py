"""Device pairing: codes, the exchange for a device token, listing and revocation."""

from __future__ import annotations

import datetime as dt
from typing import Annotated

from fastapi import APIRouter, Depends, Request, status

from backend.audit.service import record
from backend.config import Settings, get_settings
from backend.deps import Caller, CurrentCaller, CurrentDevice, DbSession, UserCaller, client_ip, require_patient_access
from backend.devices import service
from backend.devices.schemas import DeviceOut, PairIn, PairingCodeOut, PairOut
from backend.exceptions import (
    AUTH_ERRORS,
    DeviceNotFound,
    PairingCodeInvalid,
    PatientNotFound,
    TooManyLoginAttempts,
    error_responses,
)
from backend.schemas import IdPath, Page, PageParams, page_params
from backend.users import throttle
from backend.users.models import LoginAttempt

router = APIRouter(prefix="/api/v1", tags=["devices"])


@router.post(
    "/patients/{patient_id}/pairing-codes",
    response_model=PairingCodeOut,
    status_code=status.HTTP_201_CREATED,
    responses=error_responses(*AUTH_ERRORS, PatientNotFound),
)
def create_pairing_code(
    patient_id: IdPath, caller: UserCaller, db_session: DbSession, settings: Annotated[Settings, Depends(get_settings)]
) -> PairingCodeOut:
    """Creates a single-use pairing code for the patient (the patient, an assigned therapist or an admin)."""
    require_patient_access(patient_id, caller=caller, db_session=db_session, write=True)
    row, code = service.create_pairing_code(
        db_session=db_session,
        patient_id=patient_id,
        created_by_id=caller.signed_in_user.id,
        minutes=settings.PAIRING_CODE_MINUTES,
    )
    record(
        db_session=db_session,
        caller=caller,
        action="pairing_code.create",
        object_type="pairing_code",
        object_id=row.id,
        patient_id=patient_id,
    )
    return PairingCodeOut(code=code, patient_id=patient_id, expires_at=row.expires_at)


@router.post(
    "/devices/pair",
    response_model=PairOut,
    status_code=status.HTTP_201_CREATED,
    responses=error_responses(PairingCodeInvalid, TooManyLoginAttempts),
)
def pair(
    body: PairIn, request: Request, db_session: DbSession, settings: Annotated[Settings, Depends(get_settings)]
) -> PairOut:
    """Exchanges a pairing code (no other credentials) for a device token bound to the code's patient; at most
    PAIRING_MAX_FAILURES wrong codes per address within the login window."""
    ip = client_ip(request)
    attempt = throttle.claim(
        db_session=db_session,
        kind="pairing",
        email="",
        ip=ip,
        window=dt.timedelta(minutes=settings.LOGIN_WINDOW_MINUTES),
        limits=[throttle.Limit(settings.PAIRING_MAX_FAILURES, "from this address", (LoginAttempt.ip == ip,))],
    )
    device, token = service.pair(db_session=db_session, code=body.code, name=body.name)
    throttle.settle(db_session=db_session, attempt=attempt, succeeded=True)
    caller = Caller(via="device", device=device, ip=ip)
    record(
        db_session=db_session,
        caller=caller,
        action="device.pair",
        object_type="device",
        object_id=device.id,
        patient_id=device.patient_id,
    )
    return PairOut(device_id=device.id, patient_id=device.patient_id, token=token)


@router.get("/devices/me", response_model=DeviceOut, responses=error_responses(*AUTH_ERRORS))
def device_me(device: CurrentDevice) -> DeviceOut:
    """Returns the calling device (lets the agent check its token)."""
    return DeviceOut.model_validate(device)


@router.get(
    "/patients/{patient_id}/devices",
    response_model=Page[DeviceOut],
    responses=error_responses(*AUTH_ERRORS, PatientNotFound),
)
def list_devices(
    patient_id: IdPath, caller: UserCaller, db_session: DbSession, page: Annotated[PageParams, Depends(page_params)]
) -> Page[DeviceOut]:
    """Lists a patient's devices."""
    require_patient_access(patient_id, caller=caller, db_session=db_session)
    rows, total = service.list_devices(
        db_session=db_session, patient_id=patient_id, limit=page.limit, offset=page.offset
    )
    record(db_session=db_session, caller=caller, action="device.list", object_type="device", patient_id=patient_id)
    return Page[DeviceOut](
        items=[DeviceOut.model_validate(d) for d in rows], total=total, limit=page.limit, offset=page.offset
    )


@router.delete(
    "/devices/{device_id}",
    status_code=status.HTTP_204_NO_CONTENT,
    responses=error_responses(*AUTH_ERRORS, DeviceNotFound),
)
def revoke_device(device_id: IdPath, caller: CurrentCaller, db_session: DbSession) -> None:
    """Revokes a device (its patient, an assigned therapist, an admin, or the device itself); any other device id is
    404 to a device, as a missing one is, so device ids cannot be probed."""
    if caller.device is not None and caller.device.id != device_id:
        raise service.missing(device_id)
    device = service.get_device(db_session=db_session, device_id=device_id)
    if caller.device is None:
        require_patient_access(device.patient_id, caller=caller, db_session=db_session, write=True,
                               hidden_as=service.missing(device_id))  # fmt: skip
    service.revoke(db_session=db_session, device=device)
    record(
        db_session=db_session,
        caller=caller,
        action="device.revoke",
        object_type="device",
        object_id=device.id,
        patient_id=device.patient_id,
    )
