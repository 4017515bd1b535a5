"""Several server processes check for due reminders at the same moment: the database claim lets exactly one of
them send each e-mail. Runs on committed data (real transactions on separate connections), cleaned up after."""

from __future__ import annotations

import datetime as dt
import threading
import uuid
from collections.abc import Iterator

import pytest
from sqlalchemy import delete, func, select
from sqlalchemy.orm import Session, sessionmaker

from backend.plans.models import Plan
from backend.reminders.models import ReminderSent
from backend.reminders.sender import send_due
from backend.reminders.service import DueReminder, claim
from backend.users.models import User
from tests.backend.reminders.conftest import mail_settings

NOW = dt.datetime(2026, 11, 27, 7, 0, 30, tzinfo=dt.UTC)  # 08:00:30 in Europe/Berlin


@pytest.fixture
def committed_plans(engine) -> Iterator[tuple[sessionmaker[Session], list[int]]]:
    """Three patients in Europe/Berlin with plans that remind at 08:00, committed; deleted after the test."""
    factory = sessionmaker(bind=engine, expire_on_commit=False)
    tag = uuid.uuid4().hex[:8]
    with factory() as db:
        patients = [User(email=f"once-{tag}-{k}@example.org", role="patient", time_zone="Europe/Berlin")
                    for k in range(3)]  # fmt: skip
        db.add_all(patients)
        db.flush()
        plans = [Plan(patient_id=p.id, title="t", start_date=dt.date(2026, 11, 1), reminder_times=["08:00"])
                 for p in patients]  # fmt: skip
        db.add_all(plans)
        db.commit()
        ids = [p.id for p in patients]
    yield factory, ids
    with factory() as db:
        db.execute(delete(User).where(User.id.in_(ids)))  # cascades to plans and claims
        db.commit()


def test_a_second_claim_of_the_same_reminder_is_refused(committed_plans):
    factory, ids = committed_plans
    with factory() as db:
        plan_id = db.scalar(select(Plan.id).where(Plan.patient_id == ids[0]))
    reminder = DueReminder(plan_id, ids[0], dt.date(2026, 11, 27), "08:00", NOW)
    with factory() as first, factory() as second:
        assert claim(db_session=first, reminder=reminder) is not None
        assert claim(db_session=second, reminder=reminder) is None


@pytest.mark.parametrize("workers", [2, 4])
def test_workers_checking_at_once_send_each_reminder_exactly_once(committed_plans, smtp, workers):
    factory, ids = committed_plans
    inbox, port = smtp
    settings = mail_settings(port)
    start = threading.Barrier(workers)
    counts: list[int] = []
    errors: list[BaseException] = []

    def worker() -> None:
        try:
            start.wait()
            counts.append(send_due(sessions=factory, settings=settings, now=NOW))
        except BaseException as exc:  # noqa: BLE001 - reported below
            errors.append(exc)

    threads = [threading.Thread(target=worker) for _ in range(workers)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=60)
    assert not errors, errors
    assert sum(counts) == 3, f"e-mails sent per worker: {counts}"
    assert len(inbox.wait_for(3)) == 3
    with factory() as db:
        emails = db.scalars(select(User.email).where(User.id.in_(ids))).all()
        assert sorted(rcpt for (rcpt,) in inbox.recipients) == sorted(emails)
        rows = db.scalar(select(func.count()).select_from(ReminderSent).where(ReminderSent.patient_id.in_(ids)))
        assert rows == 3
