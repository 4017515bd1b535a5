"""The reminder loop each server process runs while SMTP is configured: every REMINDER_CHECK_S it claims the
reminders due (a row in reminder_sent, so that of several workers or replicas only one sends each) and e-mails
them. A failed delivery gives its claim back, so the next check tries again while the reminder is still due."""

from __future__ import annotations

import asyncio
import datetime as dt
import logging
import smtplib
from collections.abc import Callable
from contextlib import AbstractContextManager

from sqlalchemy.orm import Session

from backend.config import Settings
from backend.database import utcnow
from backend.plans.models import Plan
from backend.reminders import mail, service
from backend.reminders.models import ReminderSent
from backend.users.models import User

log = logging.getLogger(__name__)

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
            claimed = service.claim(db_session=db_session, reminder=reminder)
            if claimed is not None:
                sent += _deliver(db_session, settings, *claimed)
    return sent


def _deliver(db_session: Session, settings: Settings, row: ReminderSent, token: str) -> int:
    """E-mails one claimed reminder; returns 1 when sent, 0 when the SMTP server failed (the claim is given back)."""
    patient, plan = db_session.get(User, row.patient_id), db_session.get(Plan, row.plan_id)
    assert patient is not None and plan is not None  # the claim's foreign keys
    url = settings.PUBLIC_URL.rstrip("/") + service.UNSUBSCRIBE_PATH + token
    name = (patient.full_name or "").split(" ")[0]
    reminder = mail.Reminder(to=patient.email, name=name, locale=patient.locale, plan_title=plan.title,
                             local_time=row.local_time, unsubscribe_url=url)  # fmt: skip
    try:
        mail.send(mail.message(reminder, sender=settings.SMTP_FROM), settings)
    except (smtplib.SMTPException, OSError) as exc:
        log.warning("reminder e-mail to patient %s failed, will retry: %s", patient.id, exc)
        db_session.delete(row)
        db_session.commit()
        return 0
    row.sent_at = utcnow()
    db_session.commit()
    return 1


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
