"""Throttling of attempts at a secret (a password, a pairing code), counted before the secret is checked.

An attempt is first recorded as a failure and committed, then the failures within the window are counted with it.
Attempts in flight therefore see each other: of N parallel guesses at most `limit` get their secret checked. A
refused attempt removes its row (it checked nothing, so a patient who keeps retrying does not extend the wait); an
attempt whose secret was right is marked succeeded and stops counting.
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass

from sqlalchemy import ColumnElement, select
from sqlalchemy.orm import Session

from backend.database import utcnow
from backend.exceptions import TooManyLoginAttempts
from backend.users.models import LoginAttempt


@dataclass(frozen=True)
class Limit:
    """At most `count` failed attempts matching `where` within the window; `words` say whose, for the error."""

    count: int
    words: str
    where: tuple[ColumnElement[bool], ...]


def claim(
    *, db_session: Session, kind: str, email: str, ip: str, window: dt.timedelta, limits: list[Limit]
) -> LoginAttempt:
    """Records an attempt (as failed until settled) and returns it, or raises TooManyLoginAttempts with
    Retry-After when a limit is passed. Commits db_session, so that parallel requests see the attempt."""
    now = utcnow()
    attempt = LoginAttempt(kind=kind, email=email, ip=ip, succeeded=False, at=now)
    db_session.add(attempt)
    db_session.commit()
    passed = _first_passed(db_session=db_session, kind=kind, now=now, window=window, limits=limits)
    db_session.commit()  # ends the read: the next write starts a transaction of its own (SQLite upgrades no snapshot)
    if passed is not None:
        limit, times = passed
        withdraw(db_session=db_session, attempt=attempt)
        retry = max(1, int((times[len(times) - limit.count - 1] + window - now).total_seconds()) + 1)
        what = "logins" if kind == "password" else f"{kind} attempts"
        raise TooManyLoginAttempts(
            f"too many failed {what} {limit.words}; retry in {retry} s", headers={"Retry-After": str(retry)}
        )
    return attempt


def _first_passed(
    *, db_session: Session, kind: str, now: dt.datetime, window: dt.timedelta, limits: list[Limit]
) -> tuple[Limit, list[dt.datetime]] | None:
    """Returns the first limit passed with the times of its failures (oldest first), or None."""
    for limit in limits:
        times = sorted(
            db_session.scalars(
                select(LoginAttempt.at).where(
                    LoginAttempt.kind == kind,
                    LoginAttempt.at > now - window,
                    LoginAttempt.succeeded.is_(False),
                    *limit.where,
                )  # fmt: skip
            )
        )
        if len(times) > limit.count:
            return limit, times
    return None


def known_address(*, db_session: Session, kind: str, email: str, ip: str, since: dt.datetime) -> bool:
    """Returns whether a secret of this kind was given right for email from ip since the given time."""
    found = db_session.scalar(
        select(LoginAttempt.id)
        .where(
            LoginAttempt.kind == kind,
            LoginAttempt.email == email,
            LoginAttempt.ip == ip,
            LoginAttempt.succeeded.is_(True),
            LoginAttempt.at >= since,
        )
        .limit(1)
    )
    return found is not None


def settle(*, db_session: Session, attempt: LoginAttempt, succeeded: bool) -> None:
    """Marks a checked attempt as succeeded (it stops counting) or leaves it a failure."""
    attempt.succeeded = succeeded
    db_session.flush()


def withdraw(*, db_session: Session, attempt: LoginAttempt) -> None:
    """Removes an attempt whose secret was never checked."""
    db_session.delete(attempt)
    db_session.commit()
