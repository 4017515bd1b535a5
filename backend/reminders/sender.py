"""The reminder loop each server process runs while SMTP is configured: every REMINDER_CHECK_S it claims the
reminders due (a row in reminder_sent, so that of several workers or replicas only one sends each) and e-mails
them. A failed delivery gives its claim back, so the next check tries again while the reminder is still due."""

from __future__ import annotations

import asyncio
import datetime as dt
import logging
import smtplib
import time
from collections.abc import Callable
from contextlib import AbstractContextManager
from functools import partial
from typing import TypeVar

from sqlalchemy import Executable, delete, update
from sqlalchemy.exc import DBAPIError
from sqlalchemy.orm import Session

from backend.config import Settings
from backend.database import is_database_busy, utcnow
from backend.plans.models import Plan
from backend.reminders import mail, service
from backend.reminders.models import ReminderSent
from backend.users.models import User

log = logging.getLogger(__name__)

T = TypeVar("T")
SessionFactory = Callable[[], AbstractContextManager[Session]]


def send_due(*, sessions: SessionFactory, settings: Settings, now: dt.datetime | None = None) -> int:
    """Sends every reminder due at now (default: the current time) that no one claimed yet; returns how many this
    call sent. Each claim is committed before its e-mail goes out."""
    now = now or utcnow()
    with sessions() as db_session:
        found = service.due(db_session=db_session, settings=settings, now=now)
        db_session.rollback()
    sent = 0
    for reminder in found:
        with sessions() as db_session:
            claimed = _busy_retried(db_session, partial(service.claim, db_session=db_session, reminder=reminder))
            if claimed is not None:
                sent += _deliver(db_session, settings, *claimed)
    return sent


def _deliver(db_session: Session, settings: Settings, row: ReminderSent, token: str) -> int:
    """E-mails one claimed reminder; returns 1 when sent, 0 when the SMTP server failed (the claim is given back).

    The reading transaction ends before the e-mail goes out, and the write after it opens its own transaction
    (SQLite: a transaction that read first could not take the write lock after another process wrote)."""
    patient, plan = db_session.get(User, row.patient_id), db_session.get(Plan, row.plan_id)
    assert patient is not None and plan is not None  # the claim's foreign keys
    url = settings.PUBLIC_URL.rstrip("/") + service.UNSUBSCRIBE_PATH + token
    name = (patient.full_name or "").split(" ")[0]
    reminder = mail.Reminder(to=patient.email, name=name, locale=patient.locale, plan_title=plan.title,
                             local_time=row.local_time, unsubscribe_url=url)  # fmt: skip
    msg = mail.message(reminder, sender=settings.SMTP_FROM)
    db_session.rollback()
    try:
        mail.send(msg, settings)
    except (smtplib.SMTPException, OSError) as exc:
        log.warning("reminder e-mail to patient %s failed, will retry: %s", row.patient_id, exc)
        _write(db_session, delete(ReminderSent).where(ReminderSent.id == row.id))
        return 0
    _write(db_session, update(ReminderSent).where(ReminderSent.id == row.id).values(sent_at=utcnow()))
    return 1


def _write(db_session: Session, statement: Executable) -> None:
    """Executes and commits one statement (retried while the database is busy)."""

    def run() -> None:
        db_session.execute(statement)
        db_session.commit()

    _busy_retried(db_session, run)


def _busy_retried(db_session: Session, work: Callable[[], T], attempts: int = 20) -> T:
    """Returns work(), run again after a short wait while another process holds the database's write lock (SQLite
    answers "database is locked" at once when a transaction's snapshot went stale); other errors pass."""
    for attempt in range(attempts):
        try:
            return work()
        except DBAPIError as exc:
            db_session.rollback()
            if not is_database_busy(exc) or attempt == attempts - 1:
                raise
            time.sleep(0.02 * (attempt + 1))
    raise AssertionError("unreachable")


async def run(*, sessions: SessionFactory, settings: Settings, stop: asyncio.Event) -> None:
    """Calls send_due every REMINDER_CHECK_S (in a thread: smtplib blocks) until stop is set."""
    while not stop.is_set():
        try:
            await asyncio.to_thread(send_due, sessions=sessions, settings=settings)
        except Exception:  # noqa: BLE001 - a database or template fault must not end the loop
            log.exception("the reminder check failed; trying again in %s s", settings.REMINDER_CHECK_S)
        try:
            await asyncio.wait_for(stop.wait(), timeout=settings.REMINDER_CHECK_S)
        except TimeoutError:
            pass
