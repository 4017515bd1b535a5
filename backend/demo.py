"""The demo clinic: seeded users, patients, plans and paired home devices, served on embedded SQLite."""

from __future__ import annotations

import argparse
import datetime as dt
import os
from pathlib import Path

from sqlalchemy import select
from sqlalchemy.orm import Session

DEMO_PASSWORD = "demo-password-2026"
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


def seed_demo(db_session: Session) -> str:
    """Creates the demo clinic once (a second run changes nothing); returns the logins to print."""
    from backend.devices.service import create_pairing_code, pair
    from backend.patients.service import assign
    from backend.plans.schemas import PlanIn, PlanItemIn
    from backend.plans.service import create_plan
    from backend.users.models import User
    from backend.users.service import create_user

    if db_session.scalar(select(User).where(User.email == ADMIN[0])) is not None:
        return logins()
    create_user(db_session=db_session, email=ADMIN[0], password=DEMO_PASSWORD, role="admin", full_name=ADMIN[1])
    therapists = [
        create_user(db_session=db_session, email=e, password=DEMO_PASSWORD, role="therapist", full_name=n)
        for e, n in THERAPISTS
    ]
    today = dt.date.today()
    for i, (email, name, exercises) in enumerate(PATIENTS):
        patient = create_user(
            db_session=db_session, email=email, password=DEMO_PASSWORD, role="patient", full_name=name
        )
        therapist = therapists[i % len(therapists)]
        assign(db_session=db_session, patient=patient, therapist=therapist)
        items = [PlanItemIn(exercise_slug=s, sets=2, repetitions=10, frequency_per_week=3) for s in exercises]
        body = PlanIn(title="Home programme", start_date=today - dt.timedelta(days=28),
                      end_date=today + dt.timedelta(days=28), items=items)  # fmt: skip
        create_plan(db_session=db_session, patient_id=patient.id, therapist_id=therapist.id, body=body)
        _, code = create_pairing_code(db_session=db_session, patient_id=patient.id, created_by_id=therapist.id,
                                      minutes=15)  # fmt: skip
        pair(db_session=db_session, code=code, name=f"{name.split()[0]}'s living-room Kinect")
    return logins()


def logins() -> str:
    """Returns the demo logins as printable lines."""
    lines = [f"  password for every demo user: {DEMO_PASSWORD}", f"  admin:      {ADMIN[0]}"]
    lines += [f"  therapist:  {e}" for e, _ in THERAPISTS]
    lines += [f"  patient:    {e}" for e, _, _ in PATIENTS]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """`coach-server demo`: a fresh SQLite demo database, migrated and seeded, then the server."""
    parser = argparse.ArgumentParser(prog="coach-server demo", description=__doc__)
    parser.add_argument("--host", default="127.0.0.1")
    parser.add_argument("--port", type=int, default=8000)
    parser.add_argument("--db", type=Path, default=Path("var/demo.db"), help="SQLite file (default var/demo.db)")
    parser.add_argument("--keep", action="store_true", help="keep an existing demo database instead of a fresh one")
    args = parser.parse_args(argv)

    args.db.parent.mkdir(parents=True, exist_ok=True)
    if not args.keep:
        args.db.unlink(missing_ok=True)
    os.environ["COACH_DATABASE_URL"] = f"sqlite:///{args.db.resolve()}"
    os.environ.setdefault("COACH_ENVIRONMENT", "local")

    from backend import cli

    for step in (["migrate"], ["seed-demo"]):
        status = cli.main(step)
        if status:
            return status
    base = f"http://{args.host}:{args.port}"
    print(f"\nKinect Home Coach demo is starting on {base}\n"
          f"  API documentation (OpenAPI): {base}/docs\n"
          f"  health check:                {base}/healthz\n"
          f"  demo database:               {args.db.resolve()}\n"
          "Press Ctrl-C to stop.\n", flush=True)  # fmt: skip
    return cli.main(["serve", "--host", args.host, "--port", str(args.port)])
