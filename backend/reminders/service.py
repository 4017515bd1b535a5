"""Reminder queries and changes: a patient's reminders today, the reminders due now, claiming one before its e-mail
is sent, and unsubscribing with the link of an e-mail."""

from __future__ import annotations

import datetime as dt
from collections.abc import Iterable
from dataclasses import dataclass
from zoneinfo import ZoneInfo

from sqlalchemy import String, cast, or_, select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from backend.config import Settings
from backend.database import utcnow
from backend.exceptions import UnsubscribeLinkUnknown
from backend.plans.models import Plan
from backend.reminders import times
from backend.reminders.models import ReminderSent
from backend.reminders.schemas import RemindersOut, ReminderTimeOut
from backend.security import new_token, token_hash
from backend.users.models import User

UNSUBSCRIBE_PATH = "/unsubscribe/"  # the page (frontend.pages) behind an e-mail's link: PUBLIC_URL + this + token
UNSUBSCRIBE_TOKEN_PREFIX = "unsub_"


def patient_zone(patient: User, settings: Settings) -> ZoneInfo:
    """Returns the patient's time zone, else the server's COACH_TIME_ZONE."""
    return times.zone(patient.time_zone or settings.TIME_ZONE)


def running_plan(*, db_session: Session, patient_id: int, day: dt.date) -> Plan | None:
    """Returns the patient's plan running on day (the newest start when plans overlap), or None."""
    query = (
        select(Plan)
        .where(
            Plan.patient_id == patient_id, Plan.start_date <= day, or_(Plan.end_date.is_(None), Plan.end_date >= day)
        )
        .order_by(Plan.start_date.desc(), Plan.id.desc())
        .limit(1)
    )
    return db_session.scalar(query)


def emails_on(patient: User, settings: Settings) -> bool:
    """Returns whether the patient gets reminder e-mails: the server sends them and the patient did not stop them."""
    return settings.reminder_emails and patient.reminder_emails_off_at is None and patient.is_active


def today(*, db_session: Session, patient: User, settings: Settings, now: dt.datetime) -> RemindersOut:
    """Returns the patient's reminders on their local day at the instant now, and the next one still to come."""
    tz = patient_zone(patient, settings)
    day = times.local_date(now, tz)
    plan = running_plan(db_session=db_session, patient_id=patient.id, day=day)
    found = [
        ReminderTimeOut(time=t, due_at=times.due_at(day, t, tz), passed=times.due_at(day, t, tz) <= now)
        for t in (plan.reminder_times if plan is not None else [])
    ]
    upcoming = [r for r in found if not r.passed]
    return RemindersOut(
        time_zone=tz.key, local_date=day, times=found, next=upcoming[0] if upcoming else None,
        emails=emails_on(patient, settings),
    )  # fmt: skip


@dataclass(frozen=True)
class DueReminder:
    """One reminder e-mail to send: the plan, the patient-local day and time, and the UTC instant it is due."""

    plan_id: int
    patient_id: int
    local_date: dt.date
    local_time: str
    due_at: dt.datetime


def due(*, db_session: Session, settings: Settings, now: dt.datetime) -> list[DueReminder]:
    """Returns the reminders due at now and not claimed yet: due within the last REMINDER_LATE_MINUTES, of the plan
    running on that patient-local day, for patients who get e-mails. Three queries, whatever the number of patients."""
    late = dt.timedelta(minutes=settings.REMINDER_LATE_MINUTES)
    first, last = (now - late - dt.timedelta(days=2)).date(), (now + dt.timedelta(days=2)).date()  # every zone's today
    in_range = (Plan.start_date <= last, or_(Plan.end_date.is_(None), Plan.end_date >= first))
    with_reminders = select(Plan.patient_id).where(*in_range, cast(Plan.reminder_times, String) != "[]")
    rows = db_session.execute(
        select(User, Plan)
        .join(Plan, Plan.patient_id == User.id)
        .where(User.role == "patient", User.is_active.is_(True), User.reminder_emails_off_at.is_(None))
        .where(User.id.in_(with_reminders), *in_range)
        .order_by(User.id, Plan.start_date.desc(), Plan.id.desc())  # per patient, the newest plan first
    ).all()
    plans: dict[int, tuple[User, list[Plan]]] = {}
    for user, plan in rows:
        plans.setdefault(user.id, (user, []))[1].append(plan)
    found: list[DueReminder] = []
    for patient, newest_first in plans.values():
        tz = patient_zone(patient, settings)
        for day in sorted({times.local_date(now - late, tz), times.local_date(now, tz)}):
            running = next(
                (p for p in newest_first if p.start_date <= day and (p.end_date is None or p.end_date >= day)), None
            )
            if running is None:
                continue
            for t in running.reminder_times:
                at = times.due_at(day, t, tz)
                if now - late < at <= now:
                    found.append(DueReminder(running.id, patient.id, day, t, at))
    return _unclaimed(db_session, found, since=now - late - dt.timedelta(days=1))


def _unclaimed(db_session: Session, found: Iterable[DueReminder], *, since: dt.datetime) -> list[DueReminder]:
    query = select(ReminderSent.plan_id, ReminderSent.local_date, ReminderSent.local_time)
    claimed = {tuple(row) for row in db_session.execute(query.where(ReminderSent.due_at > since))}
    return [r for r in found if (r.plan_id, r.local_date, r.local_time) not in claimed]


def claim(*, db_session: Session, reminder: DueReminder) -> tuple[ReminderSent, str] | None:
    """Inserts and commits the row of one reminder e-mail; returns it with its new unsubscribe token, or None when
    another server (or an earlier run) claimed it first (the unique plan, day and time)."""
    token = new_token(UNSUBSCRIBE_TOKEN_PREFIX)
    row = ReminderSent(plan_id=reminder.plan_id, patient_id=reminder.patient_id, local_date=reminder.local_date,
                       local_time=reminder.local_time, due_at=reminder.due_at, token_hash=token_hash(token),
                       claimed_at=utcnow())  # fmt: skip
    db_session.add(row)
    try:
        db_session.commit()
    except IntegrityError:
        db_session.rollback()
        return None
    return row, token


def unsubscribe(*, db_session: Session, token: str) -> User:
    """Stops the reminder e-mails of the patient an e-mail's token was sent to (idempotent: the first time is kept);
    raises UnsubscribeLinkUnknown for a token of no e-mail."""
    row = db_session.scalar(select(ReminderSent).where(ReminderSent.token_hash == token_hash(token)))
    patient = db_session.get(User, row.patient_id) if row is not None else None
    if patient is None:
        raise UnsubscribeLinkUnknown("this unsubscribe link belongs to no reminder e-mail; check that it is complete")
    if patient.reminder_emails_off_at is None:
        patient.reminder_emails_off_at = utcnow()
        db_session.flush()
    return patient


def patient_of_token(*, db_session: Session, token: str) -> User | None:
    """Returns the patient an unsubscribe token was sent to, or None."""
    row = db_session.scalar(select(ReminderSent).where(ReminderSent.token_hash == token_hash(token)))
    return db_session.get(User, row.patient_id) if row is not None else None
