"""User, login-session, login-throttling and API-token queries."""

from __future__ import annotations

import datetime as dt
from collections.abc import Sequence

from sqlalchemy import func, select, update
from sqlalchemy.orm import Session

from backend.config import Settings
from backend.database import utcnow
from backend.events.hub import ACCESS_ENDED, Event, publish
from backend.exceptions import (
    EmailAlreadyRegistered,
    NotAuthenticated,
    PasswordCheckBusy,
    TokenNotFound,
    UserNotFound,
)
from backend.security import (
    API_TOKEN_PREFIX,
    SESSION_TOKEN_PREFIX,
    hash_password,
    new_csrf_secret,
    new_token,
    token_hash,
    verify_password,
)
from backend.users import throttle
from backend.users.models import ApiToken, LoginAttempt, LoginSession, User

KNOWN_ADDRESS_DAYS = 30  # a successful login from an address within this long makes it the account's known address


def get_user(*, db_session: Session, user_id: int) -> User:
    """Returns one user or raises UserNotFound."""
    user = db_session.get(User, user_id)
    if user is None:
        raise UserNotFound(f"user {user_id} does not exist")
    return user


def get_user_by_email(*, db_session: Session, email: str) -> User | None:
    """Returns the user with this e-mail (case-insensitive) or None."""
    return db_session.scalar(select(User).where(User.email == email.strip().lower()))


def create_user(
    *,
    db_session: Session,
    email: str,
    password: str | None,
    role: str,
    full_name: str = "",
    password_hash: str | None = None,
) -> User:
    """Creates a user with the hash of password, or with password_hash (one made by hash_password) when password is
    None; raises EmailAlreadyRegistered when the e-mail is taken."""
    email = email.strip().lower()
    if get_user_by_email(db_session=db_session, email=email) is not None:
        raise EmailAlreadyRegistered(f"a user with email {email} exists")
    user = User(
        email=email,
        full_name=full_name,
        role=role,
        password_hash=hash_password(password) if password else password_hash,
        is_active=True,
        created_at=utcnow(),
    )
    db_session.add(user)
    db_session.flush()
    return user


def list_users(*, db_session: Session, limit: int, offset: int, role: str | None = None) -> tuple[list[User], int]:
    """Returns one page of users (by id) and the total."""
    query = select(User)
    if role is not None:
        query = query.where(User.role == role)
    total = db_session.scalar(select(func.count()).select_from(query.subquery())) or 0
    return list(db_session.scalars(query.order_by(User.id).limit(limit).offset(offset))), total


def update_user(
    *,
    db_session: Session,
    user: User,
    full_name: str | None = None,
    is_active: bool | None = None,
    password: str | None = None,
    keep_api_tokens: bool = False,
    keep_login: LoginSession | None = None,
) -> User:
    """Changes a user; a new password ends their login sessions but keep_login (the caller's own) and their API
    tokens unless keep_api_tokens; deactivating revokes every login session and API token."""
    now = utcnow()
    if full_name is not None:
        user.full_name = full_name
    if password is not None:
        user.password_hash = hash_password(password)
        revoke_all_credentials(
            db_session=db_session, user_id=user.id, api_tokens=not keep_api_tokens, keep_login=keep_login
        )
    if is_active is not None and is_active != user.is_active:
        user.is_active = is_active
        user.deactivated_at = None if is_active else now
        if not is_active:
            revoke_all_credentials(db_session=db_session, user_id=user.id)
    db_session.flush()
    return user


def revoke_all_credentials(
    *, db_session: Session, user_id: int, api_tokens: bool = True, keep_login: LoginSession | None = None
) -> None:
    """Revokes every login session of a user but keep_login and, unless api_tokens=False, every API token; ends the
    user's open event streams (keep_login's reconnects)."""
    now = utcnow()
    publish(db_session, Event(ACCESS_ENDED, 0, {"user_id": user_id}))
    kept = keep_login.id if keep_login is not None else -1
    db_session.execute(
        update(LoginSession)
        .where(LoginSession.user_id == user_id, LoginSession.revoked_at.is_(None), LoginSession.id != kept)
        .values(revoked_at=now)
    )
    if api_tokens:
        db_session.execute(
            update(ApiToken).where(ApiToken.user_id == user_id, ApiToken.revoked_at.is_(None)).values(revoked_at=now)
        )


def login(
    *, db_session: Session, settings: Settings, email: str, password: str, ip: str
) -> tuple[User, LoginSession, str]:
    """Checks a password login and returns (user, login session, cookie token). Throttled (backend.users.throttle)
    per account and address, per address and per account (from addresses it did not sign in from lately); commits
    the attempt before the password is checked."""
    email = email.strip().lower()
    limits = [
        throttle.Limit(settings.LOGIN_MAX_FAILURES, "for this account from this address",
                       (LoginAttempt.email == email, LoginAttempt.ip == ip)),
        throttle.Limit(settings.LOGIN_MAX_FAILURES_PER_IP, "from this address", (LoginAttempt.ip == ip,)),
    ]  # fmt: skip
    # The limit over all addresses stops a guess spread over many; it would also let anyone who knows an e-mail keep
    # its owner out. An address the account signed in from lately is held only by the two limits above.
    known = throttle.known_address(db_session=db_session, kind="password", email=email, ip=ip,
                                   since=utcnow() - dt.timedelta(days=KNOWN_ADDRESS_DAYS))  # fmt: skip
    db_session.commit()  # ends the read before claim() writes (SQLite cannot upgrade a read snapshot to a write)
    if not known:
        limits.append(throttle.Limit(settings.LOGIN_MAX_FAILURES_PER_ACCOUNT, "for this account",
                                     (LoginAttempt.email == email,)))  # fmt: skip
    attempt = throttle.claim(
        db_session=db_session,
        kind="password",
        email=email,
        ip=ip,
        window=dt.timedelta(minutes=settings.LOGIN_WINDOW_MINUTES),
        limits=limits,
    )
    user = get_user_by_email(db_session=db_session, email=email)
    try:
        ok = verify_password(user.password_hash if user else None, password) and user is not None and user.is_active
    except PasswordCheckBusy:
        throttle.withdraw(db_session=db_session, attempt=attempt)
        raise
    throttle.settle(db_session=db_session, attempt=attempt, succeeded=ok)
    if not ok or user is None:
        raise NotAuthenticated("wrong e-mail or password, or the account is deactivated", keep_changes=True)
    now = utcnow()
    token = new_token(SESSION_TOKEN_PREFIX)
    session = LoginSession(
        user_id=user.id,
        token_hash=token_hash(token),
        csrf_secret=new_csrf_secret(),
        ip=ip,
        created_at=now,
        expires_at=now + dt.timedelta(hours=settings.LOGIN_SESSION_HOURS),
    )
    db_session.add(session)
    db_session.flush()
    return user, session, token


def logout(*, db_session: Session, login_session: LoginSession) -> None:
    """Ends a browser login session, and the event streams it has open."""
    login_session.revoked_at = utcnow()
    db_session.flush()
    publish(db_session, Event(ACCESS_ENDED, 0, {"login_session_id": login_session.id}))


def create_api_token(
    *, db_session: Session, user: User, name: str, scopes: Sequence[str], days: int, parent: ApiToken | None = None
) -> tuple[ApiToken, str]:
    """Creates a personal API token valid for days (no longer than its parent, the token that asked for it) and
    returns (row, secret token shown once)."""
    token, now = new_token(API_TOKEN_PREFIX), utcnow()
    expires = now + dt.timedelta(days=days)
    if parent is not None:
        expires = min(expires, parent.expires_at)
    row = ApiToken(
        user_id=user.id,
        name=name,
        token_hash=token_hash(token),
        scopes=sorted(set(scopes)),
        created_at=now,
        expires_at=expires,
        parent_id=parent.id if parent is not None else None,
    )
    db_session.add(row)
    db_session.flush()
    return row, token


def list_api_tokens(*, db_session: Session, user: User, limit: int, offset: int) -> tuple[list[ApiToken], int]:
    """Returns one page of the user's API tokens (newest first) and the total."""
    query = select(ApiToken).where(ApiToken.user_id == user.id)
    total = db_session.scalar(select(func.count()).select_from(query.subquery())) or 0
    return list(db_session.scalars(query.order_by(ApiToken.id.desc()).limit(limit).offset(offset))), total


def revoke_api_token(*, db_session: Session, user: User, token_id: int) -> ApiToken:
    """Revokes one of the user's API tokens and every token made with it, and ends their open event streams; raises
    TokenNotFound for tokens of others."""
    row = db_session.get(ApiToken, token_id)
    if row is None or row.user_id != user.id:
        raise TokenNotFound(f"API token {token_id} does not exist")
    now, ids, revoked = utcnow(), [row.id], []
    while ids:  # down the tree of tokens made with tokens, one generation a query
        db_session.execute(
            update(ApiToken).where(ApiToken.id.in_(ids), ApiToken.revoked_at.is_(None)).values(revoked_at=now)
        )
        revoked += ids
        ids = list(db_session.scalars(select(ApiToken.id).where(ApiToken.parent_id.in_(ids))))
    publish(db_session, Event(ACCESS_ENDED, 0, {"api_token_ids": revoked}))  # their open event streams end
    db_session.flush()
    db_session.refresh(row)
    return row
