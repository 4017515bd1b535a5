"""Plan queries and changes."""

from __future__ import annotations

from sqlalchemy import func, select
from sqlalchemy.orm import Session

from backend.database import utcnow
from backend.exceptions import PlanNotFound
from backend.exercises.models import Exercise
from backend.exercises.service import get_exercise
from backend.plans.models import Plan, PlanItem
from backend.plans.schemas import PlanIn, PlanItemOut, PlanOut
from backend.users.models import User


def missing(plan_id: int) -> PlanNotFound:
    """Returns the error for a plan that does not exist, or that the caller has no right to know of."""
    return PlanNotFound(f"plan {plan_id} does not exist")


def _items(db_session: Session, body: PlanIn) -> list[PlanItem]:
    items = []
    for position, item in enumerate(body.items):
        exercise = get_exercise(db_session=db_session, slug=item.exercise_slug)
        items.append(
            PlanItem(
                exercise_id=exercise.id,
                position=position,
                sets=item.sets,
                repetitions=item.repetitions,
                frequency_per_week=item.frequency_per_week,
                target_rom_deg=item.target_rom_deg,
                notes=item.notes,
            )
        )
    return items


def create_plan(*, db_session: Session, patient_id: int, therapist_id: int | None, body: PlanIn) -> Plan:
    """Creates a plan with its items; raises ExerciseNotFound for unknown slugs."""
    now = utcnow()
    plan = Plan(
        patient_id=patient_id,
        therapist_id=therapist_id,
        title=body.title,
        notes=body.notes,
        start_date=body.start_date,
        end_date=body.end_date,
        reminder_times=body.reminder_times,
        created_at=now,
        updated_at=now,
    )
    plan.items = _items(db_session, body)
    db_session.add(plan)
    db_session.flush()
    return plan


def replace_plan(*, db_session: Session, plan: Plan, body: PlanIn) -> Plan:
    """Replaces every field and item of a plan."""
    new_items = _items(db_session, body)
    plan.title, plan.notes = body.title, body.notes
    plan.start_date, plan.end_date = body.start_date, body.end_date
    plan.reminder_times = body.reminder_times
    plan.items.clear()
    db_session.flush()
    plan.items.extend(new_items)
    plan.updated_at = utcnow()
    db_session.flush()
    return plan


def patient_plan_item(*, db_session: Session, patient_id: int, plan_item_id: int) -> tuple[PlanItem, Exercise]:
    """Returns a plan item of one of the patient's plans and its exercise; raises PlanNotFound."""
    found = db_session.execute(
        select(PlanItem, Exercise)
        .join(Plan, Plan.id == PlanItem.plan_id)
        .join(Exercise, Exercise.id == PlanItem.exercise_id)
        .where(PlanItem.id == plan_item_id, Plan.patient_id == patient_id)
    ).first()
    if found is None:
        raise PlanNotFound(f"plan item {plan_item_id} is not in a plan of patient {patient_id}")
    return found[0], found[1]


def get_plan(*, db_session: Session, plan_id: int) -> Plan:
    """Returns one plan or raises PlanNotFound."""
    plan = db_session.get(Plan, plan_id)
    if plan is None:
        raise missing(plan_id)
    return plan


def list_plans(*, db_session: Session, patient_id: int, limit: int, offset: int) -> tuple[list[Plan], int]:
    """Returns one page of a patient's plans (newest start first) and the total."""
    query = select(Plan).where(Plan.patient_id == patient_id)
    total = db_session.scalar(select(func.count()).select_from(query.subquery())) or 0
    rows = db_session.scalars(query.order_by(Plan.start_date.desc(), Plan.id.desc()).limit(limit).offset(offset))
    return list(rows), total


def delete_plan(*, db_session: Session, plan: Plan) -> None:
    """Deletes a plan and its items."""
    db_session.delete(plan)
    db_session.flush()


def plan_out(*, db_session: Session, plan: Plan) -> PlanOut:
    """Returns the API form of a plan (items with their exercise slugs, the prescribing therapist's name)."""
    slugs = dict(db_session.execute(select(Exercise.id, Exercise.slug)).all())
    therapist = db_session.get(User, plan.therapist_id) if plan.therapist_id is not None else None
    return PlanOut(
        id=plan.id,
        patient_id=plan.patient_id,
        therapist_id=plan.therapist_id,
        therapist_name=(therapist.full_name or therapist.email) if therapist is not None else None,
        title=plan.title,
        notes=plan.notes,
        start_date=plan.start_date,
        end_date=plan.end_date,
        created_at=plan.created_at,
        updated_at=plan.updated_at,
        reminder_times=list(plan.reminder_times or []),
        items=[
            PlanItemOut(
                id=i.id,
                exercise_id=i.exercise_id,
                exercise_slug=slugs[i.exercise_id],
                position=i.position,
                sets=i.sets,
                repetitions=i.repetitions,
                frequency_per_week=i.frequency_per_week,
                target_rom_deg=i.target_rom_deg,
                notes=i.notes,
            )
            for i in plan.items
        ],
    )
