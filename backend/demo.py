"""The demo clinic: seeded users, patients, plans and paired home devices, served on embedded SQLite, with
simulated home agents (backend.demo_agents) uploading sessions through the HTTP API while it runs."""

from __future__ import annotations

import argparse
import datetime as dt
import errno
import importlib.util
import os
import shutil
import signal
import socket
import subprocess
import sys
from pathlib import Path

from sqlalchemy import select
from sqlalchemy.orm import Session

DEMO_PASSWORD = "demo-password-2026"
SHUTDOWN_S = 0.5  # seconds the demo server gives open connections on Ctrl-C
ADMIN = ("admin@demo.clinic", "Alex Admin")
THERAPISTS = (("therapist@demo.clinic", "Tara Therapist"), ("physio@demo.clinic", "Paul Physio"))
PATIENTS = (
    ("rose@demo.clinic", "Rose Miller", ("seated_knee_extension", "sit_to_stand")),
    ("george@demo.clinic", "George Brown", ("shoulder_abduction", "elbow_flexion")),
    ("maria@demo.clinic", "Maria Rossi", ("squat", "standing_leg_raise")),
    ("henry@demo.clinic", "Henry Clark", ("shoulder_flexion", "side_step")),
    ("ines@demo.clinic", "Ines Garcia", ("sit_to_stand", "seated_knee_extension")),
    ("walter@demo.clinic", "Walter Young", ("elbow_flexion", "shoulder_flexion")),
)
# a patient with no Kinect and no home agent: she records her sets with her own computer's camera (backend/camera)
CAMERA_PATIENT = ("clara@demo.clinic", "Clara Lens", ("squat", "seated_knee_extension"), 1)  # therapist index
# the reminder times of every demo plan (HH:MM in the patient's time zone; the server's COACH_TIME_ZONE, as the demo
# patients have none of their own): morning, afternoon and evening, so the patient page shows the next one most of
# the day
REMINDER_TIMES = ("09:00", "15:00", "20:00")


def seed_demo(db_session: Session) -> str:
    """Creates the demo clinic once (a second run changes nothing); returns the logins to print."""
    from backend.devices.service import create_pairing_code, pair
    from backend.patients.service import assign
    from backend.plans.schemas import PlanIn, PlanItemIn
    from backend.plans.service import create_plan
    from backend.security import hash_password
    from backend.users.models import User
    from backend.users.service import create_user

    if db_session.scalar(select(User).where(User.email == ADMIN[0])) is not None:
        _seed_camera_patient(db_session)  # a demo database of an earlier version gets her too
        return logins()
    # Every demo user has the one public DEMO_PASSWORD, so they share one hash of it: argon2 keeps the salt in the hash,
    # and users who share a hash share only their password, which logins() prints for all of them anyway. Hashed once
    # instead of once per user, it saves 9 of the 10 hashes (about 0.25 s of CPU each) at a fresh demo start.
    password_hash = hash_password(DEMO_PASSWORD)
    create_user(db_session=db_session, email=ADMIN[0], password=None, password_hash=password_hash, role="admin",
                full_name=ADMIN[1])  # fmt: skip
    therapists = [
        create_user(
            db_session=db_session, email=e, password=None, password_hash=password_hash, role="therapist", full_name=n
        )
        for e, n in THERAPISTS
    ]
    today = dt.date.today()
    for i, (email, name, exercises) in enumerate(PATIENTS):
        patient = create_user(db_session=db_session, email=email, password=None, password_hash=password_hash,
                              role="patient", full_name=name)  # fmt: skip
        therapist = therapists[i % len(therapists)]  # as therapist_patients() says
        assign(db_session=db_session, patient=patient, therapist=therapist)
        items = [PlanItemIn(exercise_slug=s, sets=2, repetitions=10, frequency_per_week=3) for s in exercises]
        body = PlanIn(title="Home programme", start_date=today - dt.timedelta(days=28),
                      end_date=today + dt.timedelta(days=28), items=items,
                      reminder_times=list(REMINDER_TIMES))  # fmt: skip
        create_plan(db_session=db_session, patient_id=patient.id, therapist_id=therapist.id, body=body)
        _, code = create_pairing_code(db_session=db_session, patient_id=patient.id, created_by_id=therapist.id,
                                      minutes=15)  # fmt: skip
        pair(db_session=db_session, code=code, name=f"{name.split()[0]}'s living-room Kinect")
    _seed_camera_patient(db_session, password_hash)
    return logins()


def _seed_camera_patient(db_session: Session, password_hash: str | None = None) -> None:
    """Creates CAMERA_PATIENT once: a plan of two exercises with 2 x 5 repetitions, no paired device; password_hash is
    the other demo users' hash of DEMO_PASSWORD (made here when None)."""
    from backend.patients.service import assign
    from backend.plans.schemas import PlanIn, PlanItemIn
    from backend.plans.service import create_plan
    from backend.security import hash_password
    from backend.users.models import User
    from backend.users.service import create_user

    email, name, exercises, t = CAMERA_PATIENT
    if db_session.scalar(select(User).where(User.email == email)) is not None:
        return
    therapist = db_session.scalar(select(User).where(User.email == THERAPISTS[t][0]))
    if therapist is None:
        return
    patient = create_user(db_session=db_session, email=email, password=None, role="patient", full_name=name,
                          password_hash=password_hash or hash_password(DEMO_PASSWORD))  # fmt: skip
    assign(db_session=db_session, patient=patient, therapist=therapist)
    today = dt.date.today()
    items = [PlanItemIn(exercise_slug=s, sets=2, repetitions=5, frequency_per_week=3) for s in exercises]
    body = PlanIn(title="Home programme (camera)", start_date=today - dt.timedelta(days=7),
                  end_date=today + dt.timedelta(days=56), items=items, reminder_times=list(REMINDER_TIMES))  # fmt: skip
    create_plan(db_session=db_session, patient_id=patient.id, therapist_id=therapist.id, body=body)


def logins() -> str:
    """Returns the demo logins as printable lines."""
    lines = [f"  password for every demo user: {DEMO_PASSWORD}", f"  admin:      {ADMIN[0]} (sees every patient)"]
    for i, (email, name) in enumerate(THERAPISTS):
        theirs = ", ".join(n for n, _ in therapist_patients(i))
        lines.append(f"  therapist:  {email} ({name}; patients: {theirs})")
    lines += [f"  patient:    {e} ({n}; therapist: {THERAPISTS[i % len(THERAPISTS)][1]})"
              for i, (e, n, _) in enumerate(PATIENTS)]  # fmt: skip
    email, name, _, t = CAMERA_PATIENT
    lines.append(f"  patient:    {email} ({name}; therapist: {THERAPISTS[t][1]}; no Kinect: she uses this "
                 "computer's camera)")  # fmt: skip
    return "\n".join(lines)


def therapist_patients(index: int) -> list[tuple[str, str]]:
    """Returns (name, email) of the demo patients assigned to THERAPISTS[index] (patients go round the therapists)."""
    return [(n, e) for i, (e, n, _) in enumerate(PATIENTS) if i % len(THERAPISTS) == index]


def main(argv: list[str] | None = None) -> int:
    """`coach-server demo`: the SQLite demo database (kept between runs; --fresh starts over), migrated and
    seeded, then the server and the simulated home agents."""
    parser = argparse.ArgumentParser(prog="coach-server demo", description=__doc__)
    parser.add_argument("--host", default="127.0.0.1")
    parser.add_argument("--port", type=int, default=8000)
    parser.add_argument("--db", type=Path, default=Path("var/demo.db"), help="SQLite file (default var/demo.db)")
    parser.add_argument(
        "--fresh",
        action="store_true",
        help="start over: delete the demo database and the agents' queues (kept by default)",
    )
    parser.add_argument("--no-agents", action="store_true", help="do not start the simulated home agents")
    parser.add_argument("--history-weeks", type=int, default=3, help="weeks of backdated sessions (default 3)")
    parser.add_argument("--agent-interval", type=float, nargs=2, default=(30.0, 60.0), metavar=("MIN", "MAX"),
                        help="seconds between live sessions of the simulated agents (default 30 60)")  # fmt: skip
    args = parser.parse_args(argv)
    if not args.no_agents and importlib.util.find_spec("kinect_agent.home") is None:
        print("error: the demo's simulated home agents need the agent installed beside the server (the development "
              "install: scripts/demo.sh); the server's install alone runs `coach-server demo --no-agents`",
              file=sys.stderr)  # fmt: skip
        return 2
    busy = port_in_use(args.host, args.port)
    if busy:
        print(f"error: cannot serve on {args.host}:{args.port}: {busy}; stop what uses it or choose another port "
              f"with --port, e.g. coach-server demo --port {args.port + 1}", file=sys.stderr)  # fmt: skip
        return 2

    args.db.parent.mkdir(parents=True, exist_ok=True)
    agents_home = args.db.parent / f"{args.db.stem}-agents"
    kept = args.db.exists() and not args.fresh
    if args.fresh:
        args.db.unlink(missing_ok=True)
        shutil.rmtree(agents_home, ignore_errors=True)  # their device tokens belong to the old database
    os.environ["COACH_DATABASE_URL"] = f"sqlite:///{args.db.resolve()}"
    os.environ.setdefault("COACH_ENVIRONMENT", "local")
    os.environ.setdefault("COACH_EMBEDDED_WORKER", "true")  # the demo's replays are built without a worker process

    from backend import cli

    for step in (["migrate"], ["seed-demo"]):
        status = cli.main(step)
        if status:
            return status
    base = f"http://{args.host}:{args.port}"
    print(f"\nKinect Home Coach demo is starting on {base}\n"
          f"  sign in (every role):        {base}/\n"
          f"  patient feedback screen:     {base}/patient\n"
          f"  set with this computer's camera: {base}/patient (as {CAMERA_PATIENT[0]}: \"Start with this computer's "
          "camera\")\n"
          f"  therapist dashboard:         {base}/therapist\n"
          f"  API documentation (OpenAPI): {base}/docs\n"
          f"  health check:                {base}/healthz\n"
          f"  demo database:               {args.db.resolve()} "
          f"({'kept from the last run; --fresh starts over' if kept else 'new'})\n"
          f"{_agents_line(args, agents_home)}"
          "Press Ctrl-C to stop.\n", flush=True)  # fmt: skip
    agents = None if args.no_agents else start_agents(base, agents_home, args)
    if agents is not None:
        cli.ON_STOP.append(lambda: signal_agents(agents, signal.SIGTERM))  # they stop while the server does
    # uvicorn re-raises a SIGTERM after its graceful shutdown: make it an exception so `finally` stops the agents.
    signal.signal(signal.SIGTERM, _exit_on_sigterm)
    try:  # Ctrl-C: the server ends its streams and signals the agents (cli.ON_STOP), both stop at once
        serve = ["serve", "--host", args.host, "--port", str(args.port), "--shutdown-timeout", str(SHUTDOWN_S)]
        status = cli.main(serve)
    finally:
        stop_agents(agents)
    # Everything the demo keeps is on disk now (SQLite, the agents' queues): leave without the interpreter's clean-up,
    # which spends seconds collecting numpy, scipy and numba objects on a busy machine, so that Ctrl-C ends the demo
    # within 2 s (tests/backend/test_demo_start.py).
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(status)


def port_in_use(host: str, port: int) -> str | None:
    """Returns why the server could not listen on host:port (e.g. "the port is in use"), or None when it can."""
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except socket.gaierror as exc:
        return f"unknown host ({exc.strerror})"
    family, kind, proto, _, address = infos[0]
    with socket.socket(family, kind, proto) as probe:
        probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as uvicorn does: a TIME_WAIT port is free
        try:
            probe.bind(address)
        except OSError as exc:
            return "the port is in use" if exc.errno == errno.EADDRINUSE else exc.strerror or str(exc)
    return None


def _exit_on_sigterm(*_: object) -> None:
    raise SystemExit(0)


def _agents_line(args: argparse.Namespace, agents_home: Path) -> str:
    if args.no_agents:
        return ""
    low, high = args.agent_interval
    return (f"  simulated home agents:       {len(PATIENTS)} (one per patient; {args.history_weeks} weeks of history, "
            f"then a session every {low:.0f}-{high:.0f} s; queues in {agents_home.resolve()})\n")  # fmt: skip


def start_agents(base: str, home: Path, args: argparse.Namespace) -> subprocess.Popen[bytes]:
    """Starts backend.demo_agents as a child process that pairs and uploads through the HTTP API."""
    host = base.replace("://0.0.0.0:", "://127.0.0.1:")
    low, high = args.agent_interval
    command = [sys.executable, "-m", "backend.demo_agents", "--server", host, "--home", str(home.resolve()),
               "--history-weeks", str(args.history_weeks), "--min-interval", str(low), "--max-interval", str(high),
               "--parent-pid", str(os.getpid())]  # fmt: skip
    # a session of its own: the terminal's Ctrl-C reaches the demo only, which then stops the agents with SIGTERM
    # (a Ctrl-C in the agents' middle of a filter or an upload would print tracebacks)
    return subprocess.Popen(command, start_new_session=True)


def signal_agents(agents: subprocess.Popen[bytes], sig: int) -> None:
    """Sends sig to the agents' process group (the agents and the live agent they started)."""
    try:
        os.killpg(agents.pid, sig)
    except ProcessLookupError:
        pass


def stop_agents(agents: subprocess.Popen[bytes] | None) -> None:
    """Stops the agents (SIGTERM to their group, then SIGKILL after 10 s); their queues keep whatever was not sent
    (atomic writes: any moment is safe)."""
    if agents is None:
        return
    signal_agents(agents, signal.SIGTERM)
    try:
        agents.wait(timeout=10)
    except subprocess.TimeoutExpired:
        signal_agents(agents, signal.SIGKILL)
        agents.wait()
