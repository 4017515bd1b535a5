"""`coach-server`: serve, migrate, create-user, seed-demo, demo, analyze. User errors: one line on stderr, exit 2."""

from __future__ import annotations

import argparse
import getpass
import sys
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from backend import __version__
from kinect_agent.processing.errors import ProcessingError

if TYPE_CHECKING:
    from types import FrameType

    from sqlalchemy.orm import Session

    from backend.config import Settings


class CliError(Exception):
    """A user error: printed as one line on stderr, exit status 2."""


def _settings() -> Settings:
    from pydantic import ValidationError

    from backend.config import get_settings

    try:
        return get_settings()
    except ValidationError as exc:
        first = exc.errors()[0]
        where = ".".join(str(p) for p in first.get("loc", ())) or "settings"
        raise CliError(f"bad configuration ({where}): {first.get('msg')}") from None


ON_STOP: list[Callable[[], None]] = []  # called when the server is told to stop (the demo ends its agents then)


def cmd_serve(args: argparse.Namespace) -> int:
    """Checks the schema is at head, then runs uvicorn."""
    import uvicorn

    from backend.database import get_engine
    from backend.exceptions import DatabaseNotMigrated
    from backend.main import create_app
    from backend.migrate import check_at_head

    settings = _settings()
    try:
        check_at_head(get_engine())
    except DatabaseNotMigrated as exc:
        raise CliError(str(exc)) from None
    options = serve_options(args, settings)
    if options["workers"] > 1:  # each worker builds its own app from the same environment
        uvicorn.run("backend.main:create_app", **options)
        return 0
    from backend.events.hub import HUB

    class StoppingServer(uvicorn.Server):
        """uvicorn's server that, on Ctrl-C or SIGTERM, first ends this process's open event streams (pages, home
        agents) and calls ON_STOP: the stop then waits for none of them, and no stream is cancelled mid-response
        (a traceback)."""

        def handle_exit(self, sig: int, frame: FrameType | None) -> None:
            HUB.stop_all()
            for callback in ON_STOP:
                callback()
            super().handle_exit(sig, frame)

    one = {k: v for k, v in options.items() if k not in ("factory", "workers")}
    StoppingServer(uvicorn.Config(create_app(settings), **one)).run()
    return 0


# longer than a therapist's pause between clicks and than load balancers' idle timeouts (60 s), so a client never
# reuses a connection the server is closing
KEEP_ALIVE_S = 75


def serve_options(args: argparse.Namespace, settings: Settings) -> dict[str, Any]:
    """Returns uvicorn's options for `serve`: the command line's, else the settings' (COACH_HOST, COACH_PORT,
    COACH_WORKERS, COACH_FORWARDED_ALLOW_IPS)."""
    workers = args.workers or settings.WORKERS
    return {
        "factory": workers > 1,
        "workers": workers,
        "host": args.host or settings.HOST,
        "port": args.port or settings.PORT,
        "proxy_headers": True,
        "forwarded_allow_ips": args.forwarded_allow_ips or settings.FORWARDED_ALLOW_IPS,
        "timeout_keep_alive": KEEP_ALIVE_S,
        # open event streams must not hold a stop; browsers reconnect
        "timeout_graceful_shutdown": getattr(args, "shutdown_timeout", None) or 5.0,
    }


def cmd_migrate(args: argparse.Namespace) -> int:
    """Upgrades to --revision (default head) or downgrades to --down; syncs the exercise library at head."""
    from alembic.util.exc import CommandError

    from backend.database import get_engine, get_sessionmaker
    from backend.migrate import current_revision, downgrade, head_revision, upgrade

    _settings()
    engine = get_engine()
    try:
        with engine.begin() as conn:
            if args.down is not None:
                downgrade(conn, args.down)
            else:
                upgrade(conn, args.revision)
            now = current_revision(conn)
    except CommandError as exc:
        raise CliError(f"migration failed: {exc}") from None
    if now == head_revision():
        synced = _sync_exercises(get_sessionmaker())
        print(f"database at revision {now} (head); exercise library: {synced} exercises")
    else:
        print(f"database at revision {now or 'base (empty)'}")
    return 0


def _sync_exercises(factory: Callable[[], Session]) -> int | str:
    try:
        from backend.exercises.service import sync_exercise_library

        with factory() as session, session.begin():
            return sync_exercise_library(db_session=session)
    except ModuleNotFoundError as exc:
        if exc.name == "backend.exercises.library":
            print("warning: backend.exercises.library is missing; exercise table not seeded", file=sys.stderr)
            return "not seeded"
        raise


def cmd_create_user(args: argparse.Namespace) -> int:
    """Creates a user, prompting for the password when --password is not given."""
    from backend.database import get_sessionmaker
    from backend.exceptions import AppError
    from backend.users.schemas import UserCreate
    from backend.users.service import create_user

    _settings()
    password = args.password
    if password is None:
        password = getpass.getpass("password: ")
        if password != getpass.getpass("repeat password: "):
            raise CliError("the two passwords differ")
    from pydantic import ValidationError

    try:
        body = UserCreate(email=args.email, password=password, role=args.role, full_name=args.name)
    except ValidationError as exc:
        first = exc.errors()[0]
        raise CliError(f"{'.'.join(str(p) for p in first['loc'])}: {first['msg']}") from None
    _require_migrated()
    try:
        with get_sessionmaker()() as session, session.begin():
            user = create_user(
                db_session=session, email=body.email, password=body.password, role=body.role, full_name=body.full_name
            )
            print(f"created {user.role} {user.email} (id {user.id})")
    except AppError as exc:
        raise CliError(exc.message) from None
    return 0


def _require_migrated() -> None:
    from backend.database import get_engine
    from backend.exceptions import DatabaseNotMigrated
    from backend.migrate import check_at_head

    try:
        check_at_head(get_engine())
    except DatabaseNotMigrated as exc:
        raise CliError(str(exc)) from None


def cmd_seed_demo(args: argparse.Namespace) -> int:
    """Fills the database with demo users, patients, plans and sessions (backend.demo.seed_demo)."""
    from backend.database import get_sessionmaker

    _settings()
    _require_migrated()
    from backend import demo

    with get_sessionmaker()() as session, session.begin():
        result = demo.seed_demo(session)
    if result is not None:
        print(result)
    return 0


def cmd_analyze(args: argparse.Namespace) -> int:
    """Prints the analysis report of one recording file (backend.session_texts.summary)."""
    from backend.session_texts import summary

    return summary.run(args)


def cmd_demo(args: argparse.Namespace) -> int:
    """Runs the demo clinic on a fresh embedded SQLite database (backend.demo.main)."""
    from backend.demo import main as demo_main

    return demo_main([])


def cmd_storage(args: argparse.Namespace) -> int:
    """Checks the object store against the database, or moves files between them (backend.storage.check)."""
    from backend.storage import check

    _settings()
    if args.batch < 1:
        raise CliError(f"--batch must be at least 1, got {args.batch}")
    if args.action != "init":
        _require_migrated()
    return check.run(args)


def cmd_retention(args: argparse.Namespace) -> int:
    """Removes session files older than the retention period, keeping their metrics (backend.records.retention)."""
    from backend.database import get_sessionmaker
    from backend.records.retention import apply_retention

    settings = _settings()
    if args.days is not None and args.days < 1:
        raise CliError(f"--days must be at least 1, got {args.days} (retention off: leave COACH_RETENTION_DAYS at 0)")
    days = args.days if args.days is not None else settings.RETENTION_DAYS
    if days <= 0:
        print("retention is off (COACH_RETENTION_DAYS=0): no session file removed")
        return 0
    _require_migrated()
    with get_sessionmaker()() as session:
        report = apply_retention(db_session=session, days=days)
        session.commit()
    print(report.text())
    return 0


def cmd_patient_data(args: argparse.Namespace) -> int:
    """Writes a patient's archive or progress report, or erases the patient, for an admin (backend.records.commands)."""
    from backend.database import get_sessionmaker
    from backend.exceptions import AppError
    from backend.records.commands import run

    _settings()
    _require_migrated()
    with get_sessionmaker()() as session:
        try:
            said = run(args, session)
        except AppError as exc:
            raise CliError(exc.message) from None
        session.commit()  # an erasure's stored objects are deleted now (backend.records.erasure)
    print(said)
    return 0


def cmd_reanalyze(args: argparse.Namespace) -> int:
    """Queues the re-analysis of stored sessions (backend.records.reanalysis); `coach-server worker` runs it."""
    import datetime as dt
    import time

    from backend.audit.service import record
    from backend.database import get_sessionmaker
    from backend.exceptions import InvalidInput, PatientNotFound
    from backend.jobs.queue import progress
    from backend.records.reanalysis import enqueue_reanalysis

    _settings()
    _require_migrated()
    since = None
    if args.since:
        try:
            since = dt.date.fromisoformat(args.since)
        except ValueError:
            raise CliError(f"--since must be a date like 2026-01-31, got {args.since!r}") from None
    with get_sessionmaker()() as session:
        try:
            batch, added = enqueue_reanalysis(db_session=session, patient_id=args.patient, since=since,
                                              exercise=args.exercise, pipeline=args.pipeline)  # fmt: skip
        except (PatientNotFound, InvalidInput) as exc:
            raise CliError(exc.message) from None
        # audited as POST /reanalysis is: the admin page reads a batch's scope (one patient or every one) from it
        detail = {"patient_id": args.patient, "since": args.since, "exercise": args.exercise,
                  "pipeline": args.pipeline, "via": "coach-server"}  # fmt: skip
        record(db_session=session, caller=None, action="reanalysis.queue", object_type="batch", object_id=batch,
               patient_id=args.patient, detail=detail)  # fmt: skip
        session.commit()
        what = "re-analysis with today's pipeline" if args.pipeline else "re-analysis"
        print(f"batch {batch}: {added} session(s) queued for {what} (run `coach-server worker` to do them)")
        while args.wait and added:
            p = progress(db_session=session, batch=batch)
            session.commit()
            print(f"  done {p['done']}, failed {p['failed']}, running {p['running']}, queued {p['queued']} "
                  f"of {p['total']}", file=sys.stderr)  # fmt: skip
            if p["queued"] + p["running"] == 0:
                break
            time.sleep(2.0)
    return 0


def cmd_worker(args: argparse.Namespace) -> int:
    """Runs queued jobs (re-analysis) until stopped (backend.jobs.worker)."""
    from backend.jobs import worker

    _settings()
    _require_migrated()
    return worker.main(args)


def build_parser() -> argparse.ArgumentParser:
    """Returns the parser of every subcommand."""
    parser = argparse.ArgumentParser(prog="coach-server", description="Kinect Home Coach coaching server.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    p = sub.add_parser("serve", help="run the HTTP server (refuses a database behind head)")
    p.add_argument("--host", help="bind address (default COACH_HOST)")
    p.add_argument("--port", type=int, help="port (default COACH_PORT)")
    p.add_argument("--forwarded-allow-ips", help="proxies believed in X-Forwarded-For (COACH_FORWARDED_ALLOW_IPS)")
    p.add_argument("--workers", type=int, help="worker processes, about one per core (default COACH_WORKERS)")
    p.add_argument("--shutdown-timeout", type=float, default=5.0,
                   help="seconds open connections (event streams) get to close on stop (default 5)")  # fmt: skip
    p.set_defaults(_run=cmd_serve)

    p = sub.add_parser("migrate", help="bring the database to head (or --revision / --down)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--revision", default="head", help="upgrade target (default head)")
    g.add_argument("--down", metavar="REV", help="downgrade to REV ('base' empties the database)")
    p.set_defaults(_run=cmd_migrate)

    p = sub.add_parser("create-user", help="create a user (prompts for the password when --password is omitted)")
    p.add_argument("--email", required=True)
    p.add_argument("--password", help="at least 10 characters; prompted when omitted")
    p.add_argument("--role", choices=("admin", "therapist", "patient"), default="patient")
    p.add_argument("--name", default="", help="full name")
    p.set_defaults(_run=cmd_create_user)

    p = sub.add_parser("seed-demo", help="fill the database with demo data")
    p.set_defaults(_run=cmd_seed_demo)

    p = sub.add_parser("demo", help="the demo clinic on embedded SQLite: migrate, seed, serve (`demo --help`)")
    p.set_defaults(_run=cmd_demo)

    from backend.session_texts.summary import add_arguments as analyze_arguments

    p = sub.add_parser(
        "analyze", help="the server's metrics of one recording file (any format the agent reads), as text or JSON"
    )
    analyze_arguments(p)
    p.set_defaults(_run=cmd_analyze)

    from backend.storage.check import add_arguments as storage_arguments

    p = sub.add_parser("reanalyze", help="queue stored sessions for re-analysis with today's analysis version")
    p.add_argument("--patient", type=int, help="only this patient's sessions")
    p.add_argument("--since", help="only sessions started on or after this date (YYYY-MM-DD)")
    p.add_argument("--exercise", help="only sessions of this exercise (slug, e.g. squat)")
    p.add_argument("--pipeline", action="store_true",
                   help="also filter the raw recording again where the stored file was filtered by another pipeline "
                        "version or other settings, or not at all (a new session file; the earlier one is kept). "
                        "Default: the metrics only, from the stored filtered recording")  # fmt: skip
    p.add_argument("--wait", action="store_true", help="print the progress until the batch is done")
    p.set_defaults(_run=cmd_reanalyze)

    from backend.jobs.worker import KINDS

    p = sub.add_parser("worker", help="run queued jobs (re-analysis, replays, session details, long sessions' "
                       "exports) until stopped; run several, on several machines")  # fmt: skip
    p.add_argument("--once", action="store_true", help="stop when the queue is empty")
    p.add_argument("--kinds", nargs="+", choices=KINDS, default=list(KINDS), metavar="KIND",
                   help=f"run only these kinds of job (default: all of {', '.join(KINDS)})")  # fmt: skip
    p.set_defaults(_run=cmd_worker)

    from backend.records.commands import add_arguments as patient_data_arguments

    p = sub.add_parser("patient-data", help="a patient's archive (zip) or progress report (PDF), or their erasure, "
                       "done for an admin and audited")  # fmt: skip
    patient_data_arguments(p)
    p.set_defaults(_run=cmd_patient_data)

    p = sub.add_parser("retention", help="remove session files older than COACH_RETENTION_DAYS (metrics are kept)")
    p.add_argument("--days", type=int, help="this many days instead of COACH_RETENTION_DAYS")
    p.set_defaults(_run=cmd_retention)

    p = sub.add_parser("storage", help="check the object store of session files and replays, or move files to it")
    storage_arguments(p)
    p.set_defaults(_run=cmd_storage)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Runs coach-server; returns the exit status: 2 after a one-line error of the user's (CliError), 1 after an
    internal fault of the signal processing (ProcessingError), said as such."""
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["demo"]:  # its own parser: argparse's REMAINDER cannot start with an option
        from backend.demo import main as demo_main

        return demo_main(argv[1:])
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as exc:  # --help (0) or a usage error (2, already printed by argparse)
        return int(exc.code or 0)
    try:
        return args._run(args)
    except CliError as exc:
        print(f"coach-server: error: {exc}", file=sys.stderr)
        return 2
    except ProcessingError as exc:  # the signal processing failed on input it accepted (e.g. `analyze` of a raw file)
        print(f"coach-server {args.command}: internal fault ({type(exc).__name__}): {exc}. The input was accepted; "
              "this is a fault of the program, please report it with the input file.", file=sys.stderr)  # fmt: skip
        return 1
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
