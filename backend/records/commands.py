"""`coach-server patient-data archive|report|erase`: the patient's data from the command line, as an admin.

Each command names the admin it acts for (`--admin EMAIL`, an active admin account): the audit row records them as
the API would (`patient.archive` and `patient.report` with `"via": "coach-server"` in their detail, `patient.erase`).
Erasure asks for the patient's e-mail address again (`--confirm-email`), as the API and the page do.
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import socket
from pathlib import Path

from sqlalchemy import func, select
from sqlalchemy.orm import Session

from backend.audit.service import record
from backend.config import get_settings
from backend.deps import Caller, require_patient_access
from backend.exceptions import InvalidInput
from backend.records import prepared_archive
from backend.records.erasure import erase_patient
from backend.records.report import DEFAULT_DAYS, Period, build_report
from backend.users.models import User

VIA = {"via": "coach-server"}


def _admin(db_session: Session, email: str) -> User:
    """Returns the active admin account of this e-mail address; raises InvalidInput for anyone else."""
    user = db_session.scalar(select(User).where(func.lower(User.email) == email.strip().lower()))
    if user is None or user.role != "admin" or not user.is_active:
        raise InvalidInput(f"--admin {email}: no active admin account has this e-mail address")
    return user


def _new_file(path: str) -> Path:
    """Returns path when nothing is there yet; raises InvalidInput rather than write over a file."""
    out = Path(path)
    if out.exists():
        raise InvalidInput(f"--out {path} exists already: give a new file name")
    if not out.parent.is_dir():
        raise InvalidInput(f"--out {path}: the folder {out.parent} does not exist")
    return out


def run(args: argparse.Namespace, db_session: Session) -> str:
    """Runs one patient-data command in db_session (committed by the caller on success); returns what it did."""
    if args.action in ("archive", "report") and not args.out:
        raise InvalidInput(f"{args.action} needs --out FILE")
    if args.action == "erase" and not args.confirm_email:
        raise InvalidInput("erase needs --confirm-email (the patient's e-mail address, typed again)")
    admin = _admin(db_session, args.admin)
    caller = Caller(via="cli", user=admin)
    patient = require_patient_access(args.patient_id, caller=caller, db_session=db_session)
    if args.action == "archive":
        out = _new_file(args.out)
        record(db_session=db_session, caller=caller, action="patient.archive", object_type="patient",
               object_id=patient.id, patient_id=patient.id, detail=VIA)  # fmt: skip
        return _write_archive(db_session, patient, f"admin {admin.email}", out)
    if args.action == "report":
        out = _new_file(args.out)
        period = Period.asked(_date("--from", args.start), _date("--to", args.end))
        record(db_session=db_session, caller=caller, action="patient.report", object_type="patient",
               object_id=patient.id, patient_id=patient.id,
               detail={"from": str(period.start), "to": str(period.end), **VIA})  # fmt: skip
        pdf = build_report(db_session=db_session, patient=patient, period=period,
                           made_by=admin.full_name or admin.email, paper=args.paper)  # fmt: skip
        out.write_bytes(pdf)
        return f"progress report of patient {patient.id}, {period.start} to {period.end}, written to {out}"
    if args.confirm_email.strip().lower() != patient.email.lower():
        raise InvalidInput(f"--confirm-email does not match the e-mail address of patient {patient.id}; nothing erased")
    result = erase_patient(db_session=db_session, patient=patient, caller=caller)
    return (f"patient {args.patient_id} erased: {sum(result.rows.values())} row(s), {len(result.objects)} stored "
            "object(s) (deleted once committed); the audit log keeps one patient.erase row")  # fmt: skip


def _write_archive(db_session: Session, patient: User, requested_by: str, out: Path) -> str:
    """Writes the patient's kept archive to `out`, built first unless the kept one covers today's data; returns what
    it did. The command asks for the build as the page does and runs that job itself (as a worker would; or waits
    for the worker already running it: prepared_archive.build_now), so an admin on the server gets the file without
    a worker running, the archive of the same data is built and stored once however many ask at the same moment,
    and the next ask from the page (or from here) finds it kept. Commits (the audit row with the ask)."""
    name = f"{socket.gethostname()}:{os.getpid()}:cli"  # as a worker is named (the job's locked_by)
    made = prepared_archive.build_now(db_session=db_session, patient=patient, requested_by=requested_by,
                                      settings=get_settings(), name=name)  # fmt: skip
    kept = prepared_archive.kept_archive(db_session=db_session, patient_id=patient.id)
    if kept is None:  # run keeps one for an existing patient, or raises
        raise InvalidInput(f"the archive of patient {patient.id} could not be kept")
    prepared_archive.copy_archive(kept, out)  # a chunk at a time, sha256 checked before out is replaced
    how = "made now" if made["built"] else f"the kept one of {kept.made_at:%Y-%m-%d %H:%M} UTC, still current"
    said = f"archive of patient {patient.id} ({how}) written to {out} ({kept.size} bytes)"
    if kept.incomplete:
        ids = made.get("incomplete_sessions")
        said += (f"; {kept.incomplete} session(s) incomplete, named in its README.txt"
                 + (": " + ", ".join(str(sid) for sid in ids) if ids else ""))  # fmt: skip
    return said


def _date(flag: str, value: str | None) -> dt.date | None:
    if value is None:
        return None
    try:
        return dt.date.fromisoformat(value)
    except ValueError:
        raise InvalidInput(f"{flag} must be a date like 2026-01-31, got {value!r}") from None


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Adds the patient-data subcommand's arguments."""
    p.add_argument("action", choices=("archive", "report", "erase"),
                   help="archive: everything held about the patient as one zip (README inside); report: the progress "
                        "report as PDF; erase: every row and stored object of the patient goes")  # fmt: skip
    p.add_argument("patient_id", type=int, help="the patient's id")
    p.add_argument("--admin", required=True, help="e-mail of the admin this is done for (written to the audit log)")
    p.add_argument("--out", help="archive, report: the new file to write")
    p.add_argument(
        "--from",
        dest="start",
        help=f"report: first day, YYYY-MM-DD (default: the {DEFAULT_DAYS} days up to --to, both included)",
    )
    p.add_argument("--to", dest="end", help="report: last day, YYYY-MM-DD (default: today, UTC)")
    p.add_argument("--paper", choices=("a4", "letter"), default="a4", help="report: paper size (default a4)")
    p.add_argument("--confirm-email", help="erase: the patient's e-mail address, typed again")
