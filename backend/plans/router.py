"""Plans: therapists prescribe exercises to assigned patients; patients (and their devices) read their own."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, status
from sqlalchemy.orm import Session

from backend.audit.service import record
from backend.deps import Caller, CurrentCaller, DbSession, TherapistOrAdminCaller, require_patient_access
from backend.events.hub import Event, publish
from backend.exceptions import (
    AUTH_ERRORS,
    ExerciseNotFound,
    PatientNotFound,
    PlanNotFound,
    error_responses,
)
from backend.plans import service
from backend.plans.schemas import PlanIn, PlanOut
from backend.schemas import IdPath, Page, PageParams, page_params

router = APIRouter(prefix="/api/v1", tags=["plans"])


def _audit(db_session: Session, caller: Caller, action: str, plan_id: int | None, patient_id: int) -> None:
    record(
        db_session=db_session,
        caller=caller,
        action=action,
        object_type="plan",
        object_id=plan_id,
        patient_id=patient_id,
    )


@router.get(
    "/patients/{patient_id}/plans",
    response_model=Page[PlanOut],
    responses=error_responses(*AUTH_ERRORS, PatientNotFound),
)
def list_plans(
    patient_id: IdPath, caller: CurrentCaller, db_session: DbSession, page: Annotated[PageParams, Depends(page_params)]
) -> Page[PlanOut]:
    """Lists a patient's plans, newest start first."""
    require_patient_access(patient_id, caller=caller, db_session=db_session)
    rows, total = service.list_plans(db_session=db_session, patient_id=patient_id, limit=page.limit, offset=page.offset)
    _audit(db_session, caller, "plan.list", None, patient_id)
    return Page[PlanOut](
        items=[service.plan_out(db_session=db_session, plan=p) for p in rows],
        total=total,
        limit=page.limit,
        offset=page.offset,
    )


@router.post(
    "/patients/{patient_id}/plans",
    response_model=PlanOut,
    status_code=status.HTTP_201_CREATED,
    responses=error_responses(*AUTH_ERRORS, PatientNotFound, ExerciseNotFound),
)
def create_plan(patient_id: IdPath, body: PlanIn, caller: TherapistOrAdminCaller, db_session: DbSession) -> PlanOut:
    """Prescribes a plan to a patient (an assigned therapist or an admin)."""
    require_patient_access(patient_id, caller=caller, db_session=db_session, write=True)
    therapist_id = caller.signed_in_user.id if caller.role == "therapist" else None
    plan = service.create_plan(db_session=db_session, patient_id=patient_id, therapist_id=therapist_id, body=body)
    _audit(db_session, caller, "plan.create", plan.id, patient_id)
    publish(db_session, Event("plan.changed", patient_id, {"plan_id": plan.id}))
    return service.plan_out(db_session=db_session, plan=plan)


@router.get("/plans/{plan_id}", response_model=PlanOut, responses=error_responses(*AUTH_ERRORS, PlanNotFound))
def get_plan(plan_id: IdPath, caller: CurrentCaller, db_session: DbSession) -> PlanOut:
    """Returns one plan the caller may see."""
    plan = service.get_plan(db_session=db_session, plan_id=plan_id)
    require_patient_access(plan.patient_id, caller=caller, db_session=db_session, hidden_as=service.missing(plan_id))
    _audit(db_session, caller, "plan.read", plan.id, plan.patient_id)
    return service.plan_out(db_session=db_session, plan=plan)


@router.put(
    "/plans/{plan_id}",
    response_model=PlanOut,
    responses=error_responses(*AUTH_ERRORS, PlanNotFound, ExerciseNotFound),
)
def replace_plan(plan_id: IdPath, body: PlanIn, caller: TherapistOrAdminCaller, db_session: DbSession) -> PlanOut:
    """Replaces a plan (an assigned therapist or an admin)."""
    plan = service.get_plan(db_session=db_session, plan_id=plan_id)
    require_patient_access(plan.patient_id, caller=caller, db_session=db_session, write=True,
                           hidden_as=service.missing(plan_id))  # fmt: skip
    service.replace_plan(db_session=db_session, plan=plan, body=body)
    _audit(db_session, caller, "plan.update", plan.id, plan.patient_id)
    publish(db_session, Event("plan.changed", plan.patient_id, {"plan_id": plan.id}))
    return service.plan_out(db_session=db_session, plan=plan)


@router.delete(
    "/plans/{plan_id}", status_code=status.HTTP_204_NO_CONTENT, responses=error_responses(*AUTH_ERRORS, PlanNotFound)
)
def delete_plan(plan_id: IdPath, caller: TherapistOrAdminCaller, db_session: DbSession) -> None:
    """Deletes a plan (an assigned therapist or an admin)."""
    plan = service.get_plan(db_session=db_session, plan_id=plan_id)
    require_patient_access(plan.patient_id, caller=caller, db_session=db_session, write=True,
                           hidden_as=service.missing(plan_id))  # fmt: skip
    _audit(db_session, caller, "plan.delete", plan.id, plan.patient_id)
    publish(db_session, Event("plan.changed", plan.patient_id, {"plan_id": plan.id}))
    service.delete_plan(db_session=db_session, plan=plan)
