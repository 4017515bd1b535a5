"""Request dependencies: the DB session, who is calling (cookie, API token or device token), access checks."""

from __future__ import annotations

import datetime as dt
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Annotated

from fastapi import Depends, Path, Request
from sqlalchemy import select
from sqlalchemy.orm import Session

from backend.database import get_db, utcnow
from backend.devices.models import Device
from backend.exceptions import AppError, CsrfFailed, Forbidden, InsufficientScope, NotAuthenticated, PatientNotFound
from backend.i18n import Translator, reader_translator
from backend.patients.models import TherapistPatient
from backend.security import API_TOKEN_PREFIX, DEVICE_TOKEN_PREFIX, same_secret, token_hash
from backend.users.models import ApiToken, LoginSession, User

SESSION_COOKIE = "coach_session"
CSRF_HEADER = "X-CSRF-Token"
SAFE_METHODS = frozenset({"GET", "HEAD", "OPTIONS"})
LAST_SEEN_RESOLUTION = dt.timedelta(seconds=10)  # a device's last_seen_at is kept to within this

# scope="function": commit (or roll back) before the response is sent, so a failed commit is never answered 2xx.
DbSession = Annotated[Session, Depends(get_db, scope="function")]


@dataclass
class Caller:
    """Who is calling: a user (via 'cookie' or 'token') or a device (via 'device'), with scopes and IP."""

    via: str
    user: User | None = None
    device: Device | None = None
    scopes: frozenset[str] = field(default_factory=lambda: frozenset({"read", "write"}))
    login_session: LoginSession | None = None
    api_token: ApiToken | None = None
    ip: str | None = None

    @property
    def role(self) -> str:
        """Returns 'device' for devices, else the user's role."""
        return "device" if self.device is not None else self.signed_in_user.role

    @property
    def signed_in_user(self) -> User:
        """Returns the calling user; raises Forbidden when a device calls (what UserCaller routes refuse first)."""
        if self.user is None:
            raise Forbidden("this endpoint is for users, not devices")
        return self.user


def reader_of(request: Request, caller: Caller) -> Translator:
    """Returns the language a caller reads the server's texts in: the page's (Accept-Language), else the user's
    chosen one; a therapist's among the therapist pages' locales (backend.i18n.reader_translator)."""
    locale = caller.user.locale if caller.user is not None else None
    return reader_translator(request.headers.get("accept-language"), role=caller.role, locale=locale)


def client_ip(request: Request) -> str:
    """Returns the client IP of a request ('unknown' when the transport gives none)."""
    return request.client.host if request.client else "unknown"


def _bearer(request: Request) -> str | None:
    header = request.headers.get("authorization")
    if not header:
        return None
    scheme, _, value = header.partition(" ")
    if scheme.lower() != "bearer" or not value.strip():
        raise NotAuthenticated("Authorization header must be 'Bearer <token>'")
    return value.strip()


def _from_bearer(token: str, db_session: Session, ip: str) -> Caller:
    now = utcnow()
    if token.startswith(DEVICE_TOKEN_PREFIX):
        found = db_session.execute(  # one round trip for the device and whether its patient is active
            select(Device, User.is_active)
            .join(User, User.id == Device.patient_id)
            .where(Device.token_hash == token_hash(token))
        ).first()
        if found is None or found[0].revoked_at is not None:
            raise NotAuthenticated("device token is unknown or revoked")
        device, patient_active = found
        if not patient_active:
            raise NotAuthenticated("the patient of this device is deactivated")
        if device.last_seen_at is None or now - device.last_seen_at > LAST_SEEN_RESOLUTION:
            device.last_seen_at = now  # not on every live message: a write per message would be 5 a second
        return Caller(via="device", device=device, scopes=frozenset({"read", "write"}), ip=ip)
    if token.startswith(API_TOKEN_PREFIX):
        row = db_session.scalar(select(ApiToken).where(ApiToken.token_hash == token_hash(token)))
        if row is None or row.revoked_at is not None:
            raise NotAuthenticated("API token is unknown or revoked")
        if row.expires_at <= now:
            raise NotAuthenticated(f"API token expired at {row.expires_at.isoformat(timespec='seconds')}")
        user = db_session.get(User, row.user_id)
        if user is None or not user.is_active:
            raise NotAuthenticated("the account of this API token is deactivated")
        row.last_used_at = now
        return Caller(via="token", user=user, scopes=frozenset(row.scopes), api_token=row, ip=ip)
    raise NotAuthenticated("unknown token type (expected an API token khc_... or a device token khd_...)")


def _from_cookie(cookie: str, db_session: Session, ip: str) -> Caller | None:
    found = db_session.execute(  # one round trip for the login session and its user
        select(LoginSession, User)
        .join(User, User.id == LoginSession.user_id)
        .where(LoginSession.token_hash == token_hash(cookie))
    ).first()
    if found is None:
        return None
    login, user = found
    if login.revoked_at is not None or login.expires_at <= utcnow() or not user.is_active:
        return None
    return Caller(via="cookie", user=user, login_session=login, ip=ip)


def optional_caller(request: Request, db_session: DbSession) -> Caller | None:
    """Returns the caller, or None when the request carries no credentials; bad bearer tokens raise 401."""
    ip = client_ip(request)
    token = _bearer(request)
    if token is not None:
        return _from_bearer(token, db_session, ip)
    cookie = request.cookies.get(SESSION_COOKIE)
    if cookie:
        return _from_cookie(cookie, db_session, ip)
    return None


def current_caller(request: Request, caller: Annotated[Caller | None, Depends(optional_caller)]) -> Caller:
    """Returns the authenticated caller; enforces CSRF for cookies and read/write scopes for API tokens."""
    if caller is None:
        raise NotAuthenticated("not logged in: send the session cookie or 'Authorization: Bearer <token>'")
    unsafe = request.method.upper() not in SAFE_METHODS
    if caller.via == "cookie" and unsafe:
        sent = request.headers.get(CSRF_HEADER, "")
        if not sent or not same_secret(sent, caller.login_session.csrf_secret):  # type: ignore[union-attr]
            raise CsrfFailed(f"missing or wrong {CSRF_HEADER} header (get it from GET /api/v1/auth/csrf)")
    needed = "write" if unsafe else "read"
    if needed not in caller.scopes:
        raise InsufficientScope(f"this API token lacks the '{needed}' scope")
    return caller


CurrentCaller = Annotated[Caller, Depends(current_caller)]


def current_user(caller: CurrentCaller) -> User:
    """Returns the calling user; devices are refused."""
    if caller.user is None:
        raise Forbidden("this endpoint is for users, not devices")
    return caller.user


def current_device(caller: CurrentCaller) -> Device:
    """Returns the calling device; users are refused."""
    if caller.device is None:
        raise Forbidden("this endpoint is for paired devices (Authorization: Bearer khd_...)")
    return caller.device


CurrentUser = Annotated[User, Depends(current_user)]
CurrentDevice = Annotated[Device, Depends(current_device)]


def current_user_caller(caller: CurrentCaller) -> Caller:
    """Returns the caller when it is a user (devices refused)."""
    if caller.user is None:
        raise Forbidden("this endpoint is for users, not devices")
    return caller


UserCaller = Annotated[Caller, Depends(current_user_caller)]


def require_role(*roles: str) -> Callable[[Caller], Caller]:
    """Returns a dependency that yields the calling user when their role is one of roles."""

    def dependency(caller: UserCaller) -> Caller:
        if caller.signed_in_user.role not in roles:
            raise Forbidden(f"this endpoint needs role {' or '.join(roles)}")
        return caller

    return dependency


AdminCaller = Annotated[Caller, Depends(require_role("admin"))]
TherapistOrAdminCaller = Annotated[Caller, Depends(require_role("therapist", "admin"))]


def is_assigned(*, db_session: Session, therapist_id: int, patient_id: int) -> bool:
    """Returns whether the therapist is assigned to the patient."""
    key = {"therapist_id": therapist_id, "patient_id": patient_id}
    return db_session.get(TherapistPatient, key) is not None


def may_see_patient(patient_id: int, *, caller: Caller, db_session: Session) -> bool:
    """Returns whether the caller has any right to the patient: patients themselves, their devices, assigned
    therapists, admins."""
    if caller.device is not None:
        return caller.device.patient_id == patient_id
    user = caller.user
    assert user is not None
    if user.role == "admin":
        return True
    if user.role == "patient":
        return user.id == patient_id
    return user.role == "therapist" and is_assigned(db_session=db_session, therapist_id=user.id, patient_id=patient_id)


def require_patient_access(
    patient_id: int,
    *,
    caller: Caller,
    db_session: Session,
    write: bool = False,
    allow_device: bool | None = None,
    hidden_as: AppError | None = None,
) -> User:
    """Returns the patient when the caller may see (write=False) or change (write=True) their data.

    Patients: only themselves. Therapists: only assigned patients. Admins: everyone. Devices: only their own
    patient, and for writes only when allow_device=True (uploads); allow_device=None means reads yes, writes no.
    A caller without any right to the patient cannot tell it from one that does not exist: both raise
    hidden_as (the error of the object asked for, e.g. SessionNotFound) or PatientNotFound (404). A caller who
    may see the patient but not make this change gets Forbidden (403).
    """
    if allow_device is None:
        allow_device = not write
    missing = hidden_as or PatientNotFound(f"patient {patient_id} does not exist")
    patient = db_session.get(User, patient_id)
    if patient is None or patient.role != "patient" or not may_see_patient(patient_id, caller=caller,
                                                                            db_session=db_session):  # fmt: skip
        raise missing
    if caller.device is not None and not allow_device:
        raise Forbidden(f"this device may not change the data of patient {patient_id}")
    return patient


def patient_access(
    patient_id: Annotated[int, Path(ge=1, le=2**31 - 1, description="the patient's user id")],
    caller: CurrentCaller,
    db_session: DbSession,
) -> User:
    """Dependency form of require_patient_access for routes with a {patient_id} path parameter (reads)."""
    return require_patient_access(patient_id, caller=caller, db_session=db_session)


PatientForRead = Annotated[User, Depends(patient_access)]
