"""A batch and its set's counters are written in one transaction on the product's SQLite engine, which leaves
pysqlite's own transaction handling on (it begins a transaction before the first write only): a savepoint opened
before any write would be a transaction of its own, committed (and synced to disk) apart from the counters."""

from __future__ import annotations

import datetime as dt

from sqlalchemy import event
from sqlalchemy.orm import Session

from backend.camera import service
from backend.camera.limits import CONSENT_VERSION
from backend.camera.schemas import BatchIn
from backend.database import make_engine, utcnow
from backend.exercises.models import Exercise
from backend.migrate import upgrade
from backend.plans.models import Plan, PlanItem
from backend.users.service import create_user
from tests.backend.camera.landmarks import batch, squats


def test_a_batch_is_stored_in_the_requests_transaction_with_its_counters(tmp_path):
    engine = make_engine(f"sqlite:///{tmp_path / 'coach.db'}")
    with engine.begin() as conn:
        upgrade(conn, "head")
    with Session(engine) as s:
        patient = create_user(db_session=s, email="p@example.org", password=None, role="patient")
        therapist = create_user(db_session=s, email="t@example.org", password=None, role="therapist")
        ex = Exercise(slug="test_squat", name="Squat", instructions="Squat.", defining_angles=["knee_flexion_L"],
                      plane="sagittal", normal_range_min_deg=0.0, normal_range_max_deg=120.0)  # fmt: skip
        s.add(ex)
        s.flush()
        plan = Plan(patient_id=patient.id, therapist_id=therapist.id, title="p", start_date=utcnow().date())
        plan.items.append(PlanItem(exercise_id=ex.id, sets=1, repetitions=3, frequency_per_week=3))
        s.add(plan)
        s.flush()
        service.give_consent(db_session=s, patient_id=patient.id, consent_version=CONSENT_VERSION)
        row = service.start_set(db_session=s, patient_id=patient.id, plan_item_id=plan.items[0].id,
                                model="pose_landmarker_lite")  # fmt: skip
        row.started_at = utcnow() - dt.timedelta(seconds=60)  # the frames' times are in the set's past
        set_id, pid = row.id, patient.id
        s.commit()

    seen: list[tuple[str, bool]] = []

    @event.listens_for(engine, "before_cursor_execute")
    def _record(conn, _cursor, statement, *_args) -> None:
        seen.append((statement.split()[0].upper(), conn.connection.dbapi_connection.in_transaction))

    with Session(engine) as s:
        row = service.get_set(db_session=s, patient_id=pid, set_id=set_id, for_update=True)
        body = BatchIn.model_validate(batch(0, squats(1, fps=10)[:3]))
        _, repeated = service.add_batch(db_session=s, row=row, body=body)
        s.commit()
    assert not repeated
    savepoints = [inside for what, inside in seen if what in ("SAVEPOINT", "RELEASE")]
    assert savepoints and all(savepoints), seen
