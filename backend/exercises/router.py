"""The exercise library (read-only)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, Path

from backend.deps import CurrentCaller, DbSession
from backend.exceptions import ExerciseNotFound, InsufficientScope, NotAuthenticated, error_responses
from backend.exercises import service
from backend.exercises.schemas import ExerciseOut
from backend.schemas import Page, PageParams, page_params

router = APIRouter(prefix="/api/v1/exercises", tags=["exercises"])


@router.get("", response_model=Page[ExerciseOut], responses=error_responses(NotAuthenticated, InsufficientScope))
def list_exercises(caller: CurrentCaller, db_session: DbSession, page: Annotated[PageParams, Depends(page_params)]):
    """Lists the built-in exercises by slug."""
    rows, total = service.list_exercises(db_session=db_session, limit=page.limit, offset=page.offset)
    return Page[ExerciseOut](
        items=[ExerciseOut.model_validate(e) for e in rows], total=total, limit=page.limit, offset=page.offset
    )


@router.get(
    "/{slug}",
    response_model=ExerciseOut,
    responses=error_responses(NotAuthenticated, InsufficientScope, ExerciseNotFound),
)
def get_exercise(
    slug: Annotated[str, Path(max_length=64, examples=["deep_squat"])], caller: CurrentCaller, db_session: DbSession
) -> ExerciseOut:
    """Returns one exercise."""
    return ExerciseOut.model_validate(service.get_exercise(db_session=db_session, slug=slug))
