"""The built-in exercise library: UI-PRMD movements and common seated and standing home exercises.

Each entry names the joint angle(s) (kinect_agent.body.angles.ANGLE_NAMES) whose rise and
fall define one repetition, the anatomical plane it moves in, and the normal adult range of that
angle (American Academy of Orthopaedic Surgeons values, rounded) that flexibility is judged against.
"""

from __future__ import annotations

from dataclasses import dataclass

from backend.i18n import N_
from kinect_agent.body.angles import ANGLE_NAMES


@dataclass(frozen=True)
class ExerciseSpec:
    """One exercise of the library; slugs are stable identifiers shared with the simulator."""

    slug: str
    name: str
    instructions: str
    defining_angles: tuple[str, ...]
    plane: str  # "sagittal" | "frontal" | "transverse"
    normal_range_deg: tuple[float, float]
    pose: str  # "sitting" | "standing"
    uiprmd_movement: str | None = None
    side: str = "both"  # "left" | "right" | "both"


_SPECS = (
    ExerciseSpec("deep_squat", N_("Deep squat"),
                 N_("Stand with your feet shoulder-width apart. Bend your knees and hips as if sitting back into a "
                 "chair, as far as is comfortable. Push through your heels to stand up again."),
                 ("knee_flexion_L", "knee_flexion_R"), "sagittal", (0, 135), "standing", "m01"),
    ExerciseSpec("hurdle_step", N_("Hurdle step"),
                 N_("Stand tall and lift one knee up and forward as if stepping over a low hurdle. Touch the floor "
                 "lightly with your heel and bring the leg back. Hold a chair if you need to."),
                 ("hip_flexion_L", "hip_flexion_R"), "sagittal", (0, 120), "standing", "m02"),
    ExerciseSpec("inline_lunge", N_("Inline lunge"),
                 N_("Step one foot forward in line with the other. Lower your back knee towards the floor, keeping "
                 "your back straight, then rise again."),
                 ("knee_flexion_L", "knee_flexion_R"), "sagittal", (0, 135), "standing", "m03"),
    ExerciseSpec("side_lunge", N_("Side lunge"),
                 N_("Step out to the side and bend that knee while the other leg stays straight. Push back to the "
                 "middle. Move slowly and keep your chest up."),
                 ("knee_flexion_L", "knee_flexion_R"), "frontal", (0, 135), "standing", "m04"),
    ExerciseSpec("sit_to_stand", N_("Sit to stand"),
                 N_("Sit near the front of a firm chair with your feet flat. Lean forward and stand up without using "
                 "your hands if you can. Sit down again slowly."),
                 ("knee_flexion_L", "knee_flexion_R"), "sagittal", (0, 135), "sitting", "m05"),
    ExerciseSpec("standing_active_straight_leg_raise", N_("Standing straight leg raise"),
                 N_("Stand tall holding a chair. Keep your knee straight and lift one leg forward, then lower it "
                 "slowly."),
                 ("hip_flexion_L", "hip_flexion_R"), "sagittal", (0, 90), "standing", "m06"),
    ExerciseSpec("standing_shoulder_abduction", N_("Standing shoulder abduction"),
                 N_("Stand tall with your arms by your sides. Raise one arm out to the side, thumb up, as high as is "
                 "comfortable, then lower it slowly."),
                 ("shoulder_abduction_L", "shoulder_abduction_R"), "frontal", (0, 180), "standing", "m07"),
    ExerciseSpec("standing_shoulder_extension", N_("Standing shoulder extension"),
                 N_("Stand tall and move one straight arm backwards as far as is comfortable, then bring it back to "
                 "your side."),
                 ("shoulder_flexion_L", "shoulder_flexion_R"), "sagittal", (-60, 0), "standing", "m08"),
    ExerciseSpec("standing_shoulder_rotation", N_("Standing shoulder internal and external rotation"),
                 N_("Hold your arm out to the side with the elbow bent at a right angle. Turn the forearm up, then "
                 "down, like a slow wave. Keep the elbow still."),
                 ("shoulder_rotation_L", "shoulder_rotation_R"), "transverse", (-70, 90), "standing", "m09"),
    ExerciseSpec("standing_shoulder_scaption", N_("Standing shoulder scaption"),
                 N_("Raise one arm forward and a little out to the side, thumb up, as high as is comfortable, then "
                 "lower it slowly."),
                 ("shoulder_abduction_L", "shoulder_abduction_R"), "frontal", (0, 180), "standing", "m10"),
    ExerciseSpec("shoulder_abduction", N_("Shoulder abduction"),
                 N_("Stand or sit up tall. Lift your arms out to the sides, as high as is comfortable, then lower "
                 "them slowly. Breathe out as you lift."),
                 ("shoulder_abduction_L", "shoulder_abduction_R"), "frontal", (0, 180), "standing"),
    ExerciseSpec("shoulder_flexion", N_("Shoulder flexion"),
                 N_("Stand or sit up tall. Lift your arms forward and up, as high as is comfortable, then lower them "
                 "slowly."),
                 ("shoulder_flexion_L", "shoulder_flexion_R"), "sagittal", (0, 180), "standing"),
    ExerciseSpec("elbow_flexion", N_("Elbow flexion"),
                 N_("Sit up tall with your arms by your sides. Bend your elbows to bring your hands towards your "
                 "shoulders, then straighten them slowly."),
                 ("elbow_flexion_L", "elbow_flexion_R"), "sagittal", (0, 150), "sitting"),
    ExerciseSpec("seated_knee_extension", N_("Seated knee extension"),
                 N_("Sit in a firm chair. Straighten one knee until the leg is level, hold for a moment, then lower "
                 "the foot back to the floor."),
                 ("knee_flexion_L", "knee_flexion_R"), "sagittal", (0, 135), "sitting"),
    ExerciseSpec("squat", N_("Mini squat"),
                 N_("Stand holding the back of a chair. Bend your knees a little as if starting to sit, keep your "
                 "heels down, then stand tall again."),
                 ("knee_flexion_L", "knee_flexion_R"), "sagittal", (0, 135), "standing"),
    ExerciseSpec("standing_leg_raise", N_("Standing leg raise"),
                 N_("Stand holding a chair. Lift one leg forward with the knee straight, then lower it slowly. Keep "
                 "your back upright."),
                 ("hip_flexion_L", "hip_flexion_R"), "sagittal", (0, 90), "standing"),
    ExerciseSpec("side_step", N_("Side leg raise"),
                 N_("Stand holding a chair. Lift one leg out to the side with your toes pointing forward, then bring "
                 "it back. Keep your body upright."),
                 ("hip_abduction_L", "hip_abduction_R"), "frontal", (0, 45), "standing"),
)  # fmt: skip

EXERCISES: dict[str, ExerciseSpec] = {spec.slug: spec for spec in _SPECS}

for _spec in _SPECS:
    _unknown = set(_spec.defining_angles) - set(ANGLE_NAMES)
    if _unknown:
        raise ValueError(f"exercise {_spec.slug}: unknown defining angles {sorted(_unknown)}")
