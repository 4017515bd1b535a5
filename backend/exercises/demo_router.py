"""GET /api/v1/exercises/{slug}/demonstration: how an exercise looks, for the patient page's looping figure."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Path, Response

from backend.deps import CurrentCaller, DbSession
from backend.exceptions import ExerciseNotFound, NotAuthenticated, error_responses
from backend.exercises import service
from backend.exercises.demonstration import DemonstrationOut, demonstration, view_for

router = APIRouter(prefix="/api/v1/exercises", tags=["exercises"])


@router.get(
    "/{slug}/demonstration",
    response_model=DemonstrationOut,
    responses=error_responses(NotAuthenticated, ExerciseNotFound),
)
def get_demonstration(
    slug: Annotated[str, Path(max_length=64, examples=["elbow_flexion"])],
    caller: CurrentCaller,
    db_session: DbSession,
    response: Response,
) -> DemonstrationOut:
    """Returns one repetition of the exercise as 2D joint positions over time (side view for movements in the
    sagittal plane, front view otherwise), from the simulator's motion library; no frames when it has no movement
    for the exercise."""
    exercise = service.get_exercise(db_session=db_session, slug=slug)
    response.headers["Cache-Control"] = "private, max-age=3600"
    return demonstration(exercise.slug, view_for(exercise.plane), exercise.pose)
