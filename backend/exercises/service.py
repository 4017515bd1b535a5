"""Exercise library queries, and syncing the table from backend.exercises.library.LIBRARY."""

from __future__ import annotations

from sqlalchemy import func, select
from sqlalchemy.orm import Session

from backend.database import utcnow
from backend.exceptions import ExerciseNotFound
from backend.exercises.models import Exercise


def sync_exercise_library(*, db_session: Session) -> int:
    """Inserts or updates one row per entry of backend.exercises.library.LIBRARY; returns the number synced."""
    from backend.exercises.library import LIBRARY

    existing = {e.slug: e for e in db_session.scalars(select(Exercise))}
    for slug, entry in LIBRARY.items():
        row = existing.get(slug) or Exercise(slug=slug, created_at=utcnow())
        spec = entry.spec
        row.name = entry.name
        row.instructions = entry.instructions
        row.defining_angles = list(spec.defining_angles)
        row.plane = spec.plane
        row.normal_range_min_deg = float(spec.normal_range_deg[0])
        row.normal_range_max_deg = float(spec.normal_range_deg[1])
        row.pose = spec.pose
        row.uiprmd_movement = spec.uiprmd_movement
        db_session.add(row)
    db_session.flush()
    return len(LIBRARY)


def list_exercises(*, db_session: Session, limit: int, offset: int) -> tuple[list[Exercise], int]:
    """Returns one page of exercises (by slug) and the total."""
    total = db_session.scalar(select(func.count()).select_from(Exercise)) or 0
    rows = db_session.scalars(select(Exercise).order_by(Exercise.slug).limit(limit).offset(offset))
    return list(rows), total


def get_exercise(*, db_session: Session, slug: str) -> Exercise:
    """Returns the exercise with this slug or raises ExerciseNotFound."""
    row = db_session.scalar(select(Exercise).where(Exercise.slug == slug))
    if row is None:
        raise ExerciseNotFound(f"exercise '{slug}' does not exist")
    return row
