"""The built-in exercise library as a reader meets it: each exercise's name and instructions (marked for the
catalogues with backend.i18n, written in the reader's language), over what the analysis knows of it
(kinect_agent.analysis.exercise: its slug, defining angles, plane, normal range, pose, UI-PRMD movement), found by
slug.
"""

from __future__ import annotations

from dataclasses import dataclass

from backend.i18n import N_
from kinect_agent.analysis.exercise import EXERCISES as ANALYSED
from kinect_agent.analysis.exercise import ExerciseSpec


@dataclass(frozen=True)
class LibraryExercise:
    """One exercise of the library: the analysis' spec and the words a reader sees (English msgids)."""

    spec: ExerciseSpec
    name: str
    instructions: str

    @property
    def slug(self) -> str:
        return self.spec.slug


_WORDS: dict[str, tuple[str, str]] = {  # slug: (name, instructions)
    "deep_squat": (N_("Deep squat"),
        N_("Stand with your feet shoulder-width apart. Bend your knees and hips as if sitting back into a "
        "chair, as far as is comfortable. Push through your heels to stand up again.")),
    "hurdle_step": (N_("Hurdle step"),
        N_("Stand tall and lift one knee up and forward as if stepping over a low hurdle. Touch the floor "
        "lightly with your heel and bring the leg back. Hold a chair if you need to.")),
    "inline_lunge": (N_("Inline lunge"),
        N_("Step one foot forward in line with the other. Lower your back knee towards the floor, keeping "
        "your back straight, then rise again.")),
    "side_lunge": (N_("Side lunge"),
        N_("Step out to the side and bend that knee while the other leg stays straight. Push back to the "
        "middle. Move slowly and keep your chest up.")),
    "sit_to_stand": (N_("Sit to stand"),
        N_("Sit near the front of a firm chair with your feet flat. Lean forward and stand up without using "
        "your hands if you can. Sit down again slowly.")),
    "standing_active_straight_leg_raise": (N_("Standing straight leg raise"),
        N_("Stand tall holding a chair. Keep your knee straight and lift one leg forward, then lower it "
        "slowly.")),
    "standing_shoulder_abduction": (N_("Standing shoulder abduction"),
        N_("Stand tall with your arms by your sides. Raise one arm out to the side, thumb up, as high as is "
        "comfortable, then lower it slowly.")),
    "standing_shoulder_extension": (N_("Standing shoulder extension"),
        N_("Stand tall and move one straight arm backwards as far as is comfortable, then bring it back to "
        "your side.")),
    "standing_shoulder_rotation": (N_("Standing shoulder internal and external rotation"),
        N_("Hold your arm out to the side with the elbow bent at a right angle. Turn the forearm up, then "
        "down, like a slow wave. Keep the elbow still.")),
    "standing_shoulder_scaption": (N_("Standing shoulder scaption"),
        N_("Raise one arm forward and a little out to the side, thumb up, as high as is comfortable, then "
        "lower it slowly.")),
    "shoulder_abduction": (N_("Shoulder abduction"),
        N_("Stand or sit up tall. Lift your arms out to the sides, as high as is comfortable, then lower "
        "them slowly. Breathe out as you lift.")),
    "shoulder_flexion": (N_("Shoulder flexion"),
        N_("Stand or sit up tall. Lift your arms forward and up, as high as is comfortable, then lower them "
        "slowly.")),
    "elbow_flexion": (N_("Elbow flexion"),
        N_("Sit up tall with your arms by your sides. Bend your elbows to bring your hands towards your "
        "shoulders, then straighten them slowly.")),
    "seated_knee_extension": (N_("Seated knee extension"),
        N_("Sit in a firm chair. Straighten one knee until the leg is level, hold for a moment, then lower "
        "the foot back to the floor.")),
    "squat": (N_("Mini squat"),
        N_("Stand holding the back of a chair. Bend your knees a little as if starting to sit, keep your "
        "heels down, then stand tall again.")),
    "standing_leg_raise": (N_("Standing leg raise"),
        N_("Stand holding a chair. Lift one leg forward with the knee straight, then lower it slowly. Keep "
        "your back upright.")),
    "side_step": (N_("Side leg raise"),
        N_("Stand holding a chair. Lift one leg out to the side with your toes pointing forward, then bring "
        "it back. Keep your body upright.")),
}  # fmt: skip

if set(_WORDS) != set(ANALYSED):
    raise ValueError(f"the library's words and the analysed exercises differ: {sorted(set(_WORDS) ^ set(ANALYSED))}")

LIBRARY: dict[str, LibraryExercise] = {slug: LibraryExercise(spec, *_WORDS[slug]) for slug, spec in ANALYSED.items()}
