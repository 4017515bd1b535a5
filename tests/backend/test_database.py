"""Request sessions commit on success and roll back on error; timestamps come back timezone-aware UTC."""

from __future__ import annotations

import datetime as dt
from collections.abc import Generator

import pytest
from sqlalchemy import select

from backend.database import request_session
from backend.exceptions import AppError, NotAuthenticated
from backend.users.models import LoginAttempt, User


def _run(db_session, error: BaseException | None) -> None:
    gen = request_session(db_session)
    assert isinstance(gen, Generator)  # FastAPI throws a request's error into it
    session = next(gen)
    session.add(LoginAttempt(email="x@example.org", ip="1.2.3.4", succeeded=False))
    session.flush()
    if error is None:
        with pytest.raises(StopIteration):
            next(gen)
    else:
        with pytest.raises(type(error)):
            gen.throw(error)


def _count(db_session) -> int:
    return len(db_session.scalars(select(LoginAttempt).where(LoginAttempt.email == "x@example.org")).all())


def test_success_commits(db_session):
    _run(db_session, None)
    assert _count(db_session) == 1


def test_error_rolls_back(db_session):
    _run(db_session, AppError("boom"))
    assert _count(db_session) == 0


def test_keep_changes_error_commits(db_session):
    _run(db_session, NotAuthenticated("wrong password", keep_changes=True))
    assert _count(db_session) == 1


def test_timestamps_are_utc_aware(db_session, make_user):
    user = make_user("patient")
    db_session.expire_all()
    loaded = db_session.get(User, user.id)
    assert loaded.created_at.tzinfo is not None and loaded.created_at.utcoffset() == dt.timedelta(0)


def test_naive_datetime_is_refused(db_session, make_user):
    user = make_user("patient")
    user.deactivated_at = dt.datetime(2026, 1, 1)
    with pytest.raises(Exception, match="naive datetime"):
        db_session.flush()
