"""What the analysis knows of each exercise of the library: UI-PRMD movements and common seated and standing home
exercises.

Each entry names the joint angle(s) (kinect_agent.body.angles.ANGLE_NAMES) whose rise and fall define one
repetition, the anatomical plane it moves in, and the normal adult range of that angle (American Academy of
Orthopaedic Surgeons values, rounded, degrees) that flexibility is judged against. The names and instructions a
reader sees are the server's (backend.exercises.library, by slug), in the reader's language.
"""

from __future__ import annotations

from dataclasses import dataclass

from kinect_agent.analysis.errors import UnknownExercise
from kinect_agent.body.angles import ANGLE_NAMES


@dataclass(frozen=True)
class ExerciseSpec:
    """One exercise as the analysis reads it; slugs are stable identifiers shared with the simulator and the server."""

    slug: str
    defining_angles: tuple[str, ...]
    plane: str  # "sagittal" | "frontal" | "transverse"
    normal_range_deg: tuple[float, float]
    pose: str  # "sitting" | "standing"
    uiprmd_movement: str | None = None
    side: str = "both"  # "left" | "right" | "both"


_KNEES, _HIPS = ("knee_flexion_L", "knee_flexion_R"), ("hip_flexion_L", "hip_flexion_R")
_ABDUCTION, _FLEXION = ("shoulder_abduction_L", "shoulder_abduction_R"), ("shoulder_flexion_L", "shoulder_flexion_R")

_SPECS = (
    ExerciseSpec("deep_squat", _KNEES, "sagittal", (0, 135), "standing", "m01"),
    ExerciseSpec("hurdle_step", _HIPS, "sagittal", (0, 120), "standing", "m02"),
    ExerciseSpec("inline_lunge", _KNEES, "sagittal", (0, 135), "standing", "m03"),
    ExerciseSpec("side_lunge", _KNEES, "frontal", (0, 135), "standing", "m04"),
    ExerciseSpec("sit_to_stand", _KNEES, "sagittal", (0, 135), "sitting", "m05"),
    ExerciseSpec("standing_active_straight_leg_raise", _HIPS, "sagittal", (0, 90), "standing", "m06"),
    ExerciseSpec("standing_shoulder_abduction", _ABDUCTION, "frontal", (0, 180), "standing", "m07"),
    ExerciseSpec("standing_shoulder_extension", _FLEXION, "sagittal", (-60, 0), "standing", "m08"),
    ExerciseSpec("standing_shoulder_rotation", ("shoulder_rotation_L", "shoulder_rotation_R"), "transverse",
                 (-70, 90), "standing", "m09"),
    ExerciseSpec("standing_shoulder_scaption", _ABDUCTION, "frontal", (0, 180), "standing", "m10"),
    ExerciseSpec("shoulder_abduction", _ABDUCTION, "frontal", (0, 180), "standing"),
    ExerciseSpec("shoulder_flexion", _FLEXION, "sagittal", (0, 180), "standing"),
    ExerciseSpec("elbow_flexion", ("elbow_flexion_L", "elbow_flexion_R"), "sagittal", (0, 150), "sitting"),
    ExerciseSpec("seated_knee_extension", _KNEES, "sagittal", (0, 135), "sitting"),
    ExerciseSpec("squat", _KNEES, "sagittal", (0, 135), "standing"),
    ExerciseSpec("standing_leg_raise", _HIPS, "sagittal", (0, 90), "standing"),
    ExerciseSpec("side_step", ("hip_abduction_L", "hip_abduction_R"), "frontal", (0, 45), "standing"),
)  # fmt: skip

EXERCISES: dict[str, ExerciseSpec] = {spec.slug: spec for spec in _SPECS}

for _spec in _SPECS:
    _unknown = set(_spec.defining_angles) - set(ANGLE_NAMES)
    if _unknown:
        raise ValueError(f"exercise {_spec.slug}: unknown defining angles {sorted(_unknown)}")


def get_exercise(slug: str) -> ExerciseSpec:
    """Returns the exercise `slug`; raises UnknownExercise listing the known slugs."""
    if slug not in EXERCISES:
        raise UnknownExercise(f"unknown exercise {slug!r}; known exercises: {', '.join(sorted(EXERCISES))}")
    return EXERCISES[slug]
