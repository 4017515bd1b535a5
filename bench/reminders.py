"""Reminder e-mails (issue 23, point 6): how long one check for due reminders takes, and that several workers checking
at once send each e-mail exactly once, against a real SMTP server (aiosmtpd, a test dependency).

    python bench/reminders.py [--patients 1000] [--workers 4] [--db URL] [--json OUT]

Setup (not measured): a fresh database (an SQLite file in a temp folder, or --db: a PostgreSQL URL whose schema
coach_bench_reminders is made and dropped), migrated, with --patients patients in 6 time zones; every second one has a
plan with reminder times at 08:00 and 18:30 local, the others a plan without. Measured: one `due` query at an instant
when the 08:00 reminders of two zones are due (median of 5), then --workers threads calling send_due at the same
instant through one SMTP server. Prints the e-mails expected, received, duplicated and the seconds each part took.
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import statistics
import tempfile
import threading
import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path

from aiosmtpd.controller import Controller
from aiosmtpd.smtp import SMTP, Envelope
from aiosmtpd.smtp import Session as SMTPSession
from sqlalchemy import Engine, create_engine, text
from sqlalchemy.orm import Session, sessionmaker

from backend.config import Settings
from backend.database import import_all_models, make_engine
from backend.migrate import upgrade
from backend.plans.models import Plan
from backend.reminders import service
from backend.reminders.sender import send_due
from backend.users.models import User

ZONES = ("Europe/Berlin", "Europe/London", "America/New_York", "Asia/Tokyo", "Europe/Madrid", "Australia/Sydney")
NOW = dt.datetime(2026, 11, 27, 7, 0, 30, tzinfo=dt.UTC)  # 08:00:30 in Berlin and Madrid (UTC+1)


class Inbox:
    """Counts the recipients of the e-mails an aiosmtpd server received."""

    def __init__(self) -> None:
        self.recipients: Counter[str] = Counter()

    async def handle_DATA(self, server: SMTP, session: SMTPSession, envelope: Envelope) -> str:  # noqa: N802 (aiosmtpd's hook name)
        self.recipients.update(envelope.rcpt_tos)
        return "250 OK"


def _engine(url: str | None, folder: Path) -> tuple[Engine, Callable[[], None]]:
    """Returns (engine on a SQLite file in folder, or on a fresh schema of url; the cleanup callable)."""
    if url is None:
        return make_engine(f"sqlite:///{folder / 'bench.db'}"), lambda: None
    admin = create_engine(url, isolation_level="AUTOCOMMIT")
    with admin.connect() as conn:
        conn.execute(text("DROP SCHEMA IF EXISTS coach_bench_reminders CASCADE"))
        conn.execute(text("CREATE SCHEMA coach_bench_reminders"))
    engine = create_engine(url, connect_args={"options": "-csearch_path=coach_bench_reminders"})

    def drop() -> None:
        engine.dispose()
        with admin.connect() as conn:
            conn.execute(text("DROP SCHEMA IF EXISTS coach_bench_reminders CASCADE"))

    return engine, drop


def _seed(engine: Engine, patients: int) -> int:
    """Adds the patients and plans; returns how many 08:00 reminders are due at NOW."""
    with Session(engine) as db:
        users = [User(email=f"p{k}@bench.example.org", role="patient", time_zone=ZONES[k % len(ZONES)])
                 for k in range(patients)]  # fmt: skip
        db.add_all(users)
        db.flush()
        start = dt.date(2026, 11, 1)
        times = [["08:00", "18:30"] if k % 2 == 0 else [] for k in range(patients)]
        db.add_all(
            Plan(patient_id=u.id, title="bench", start_date=start, reminder_times=t)
            for u, t in zip(users, times, strict=True)
        )
        db.commit()
    at_eight = ("Europe/Berlin", "Europe/Madrid")
    return sum(1 for k in range(patients) if k % 2 == 0 and ZONES[k % len(ZONES)] in at_eight)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--patients", type=int, default=1000)
    parser.add_argument("--workers", type=int, default=4)
    parser.add_argument("--db", help="PostgreSQL URL (default: a fresh SQLite file)")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args()
    import_all_models()
    with tempfile.TemporaryDirectory() as folder:
        engine, drop = _engine(args.db, Path(folder))
        try:
            with engine.begin() as conn:
                upgrade(conn, "head")
            expected = _seed(engine, args.patients)
            inbox = Inbox()
            with socket_port() as port:
                controller = Controller(inbox, hostname="127.0.0.1", port=port)
                controller.start()
                settings = Settings(
                    SMTP_HOST="127.0.0.1",
                    SMTP_PORT=port,
                    SMTP_STARTTLS=False,
                    SMTP_FROM="coach@bench.example.org",
                    PUBLIC_URL="https://coach.example.org",
                )
                factory = sessionmaker(bind=engine, expire_on_commit=False)
                due_s = []
                for _ in range(5):
                    with factory() as db:
                        t0 = time.perf_counter()
                        found = service.due(db_session=db, settings=settings, now=NOW)
                        due_s.append(time.perf_counter() - t0)
                counts: list[int] = []
                start = threading.Barrier(args.workers)

                def worker() -> None:
                    start.wait()
                    counts.append(send_due(sessions=factory, settings=settings, now=NOW))

                t0 = time.perf_counter()
                threads = [threading.Thread(target=worker) for _ in range(args.workers)]
                for t in threads:
                    t.start()
                for t in threads:
                    t.join()
                send_s = time.perf_counter() - t0
                time.sleep(0.5)
                controller.stop()
        finally:
            engine.dispose()
            drop()
    out = {
        "database": "postgresql" if args.db else "sqlite", "patients": args.patients, "workers": args.workers,
        "due_found": len(found), "expected": expected, "sent_per_worker": counts,
        "received": sum(inbox.recipients.values()),
        "duplicated": sum(n - 1 for n in inbox.recipients.values() if n > 1),
        "due_query_s_median": round(statistics.median(due_s), 4), "send_all_s": round(send_s, 2),
    }  # fmt: skip
    print(json.dumps(out, indent=2))
    if args.json:
        args.json.write_text(json.dumps(out, indent=2))


class socket_port:  # noqa: N801 (used as a context manager like a function)
    """Yields a free TCP port of 127.0.0.1."""

    def __enter__(self) -> int:
        import socket

        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            return s.getsockname()[1]

    def __exit__(self, *exc: object) -> None:
        return None


if __name__ == "__main__":
    main()
