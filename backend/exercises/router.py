"""The exercise library (read-only)."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends, Path, Request

from backend.deps import CurrentCaller, DbSession
from backend.exceptions import ExerciseNotFound, InsufficientScope, NotAuthenticated, error_responses
from backend.exercises import service
from backend.exercises.models import Exercise
from backend.exercises.schemas import ExerciseOut
from backend.i18n import negotiate, translator
from backend.schemas import Page, PageParams, page_params

router = APIRouter(prefix="/api/v1/exercises", tags=["exercises"])


def _out(exercise: Exercise, request: Request) -> ExerciseOut:
    """Returns an exercise with its name and instructions in the request's Accept-Language (English otherwise)."""
    out = ExerciseOut.model_validate(exercise)
    t = translator(negotiate(request.headers.get("accept-language")))
    return out.model_copy(update={"name": t.gettext(out.name), "instructions": t.gettext(out.instructions)})


@router.get("", response_model=Page[ExerciseOut], responses=error_responses(NotAuthenticated, InsufficientScope))
def list_exercises(
    request: Request, caller: CurrentCaller, db_session: DbSession, page: Annotated[PageParams, Depends(page_params)]
) -> Page[ExerciseOut]:
    """Lists the built-in exercises by slug (names and instructions in the Accept-Language asked for, if it is one
    of the library's: en, de, es, fr)."""
    rows, total = service.list_exercises(db_session=db_session, limit=page.limit, offset=page.offset)
    return Page[ExerciseOut](items=[_out(e, request) for e in rows], total=total, limit=page.limit, offset=page.offset)


@router.get(
    "/{slug}",
    response_model=ExerciseOut,
    responses=error_responses(NotAuthenticated, InsufficientScope, ExerciseNotFound),
)
def get_exercise(
    slug: Annotated[str, Path(max_length=64, examples=["deep_squat"])],
    request: Request,
    caller: CurrentCaller,
    db_session: DbSession,
) -> ExerciseOut:
    """Returns one exercise (name and instructions in the Accept-Language asked for, as the list)."""
    return _out(service.get_exercise(db_session=db_session, slug=slug), request)
