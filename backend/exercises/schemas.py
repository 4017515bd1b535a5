"""Exercise bodies."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict, Field


class ExerciseOut(BaseModel):
    """One exercise of the built-in library."""

    model_config = ConfigDict(from_attributes=True)
    id: int
    slug: str = Field(examples=["deep_squat"])
    name: str = Field(examples=["Deep squat"])
    instructions: str
    defining_angles: list[str] = Field(examples=[["knee_flexion_left", "knee_flexion_right"]])
    plane: str = Field(examples=["sagittal"])
    normal_range_min_deg: float = Field(examples=[0.0])
    normal_range_max_deg: float = Field(examples=[120.0])
    pose: str = Field(examples=["standing"])
    uiprmd_movement: str | None = Field(examples=["m03"])
    mdc95_rom_deg: float | None = Field(
        description="minimal detectable change of the range of motion between two sessions (MDC95, degrees, from "
        "repeated simulated sessions); null: not measured",
        examples=[25.5],
    )
