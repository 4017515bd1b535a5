"""Request and response bodies of camera sets."""

from __future__ import annotations

import datetime as dt
from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field

from backend.camera.limits import MAX_FRAMES_PER_BATCH, MODELS, N_LANDMARKS

ModelName = Literal[MODELS]  # type: ignore[valid-type]
Vec3 = Annotated[list[float], Field(min_length=3, max_length=3)]
Landmarks = Annotated[list[Vec3], Field(min_length=N_LANDMARKS, max_length=N_LANDMARKS)]


class ConsentIn(BaseModel):
    """The consent text the patient agreed to (its version, as the page shows it)."""

    model_config = ConfigDict(extra="forbid")

    consent_version: str = Field(min_length=1, max_length=16, examples=["2026-11-27"])


class ConsentOut(BaseModel):
    """Whether the patient agreed to the current consent text, and when."""

    patient_id: int = Field(examples=[12])
    consent_version: str = Field(description="the version the page must show and send", examples=["2026-11-27"])
    given: bool = Field(description="the patient agreed to this version")
    given_at: dt.datetime | None = None


class CameraStartIn(BaseModel):
    """Which exercise of the patient's plan to record, and which model the page runs."""

    model_config = ConfigDict(extra="forbid")

    plan_item_id: int = Field(ge=1, le=2**31 - 1, description="an item of the patient's current plan", examples=[41])
    model: ModelName = Field(description="the landmarker model the page loaded", examples=["pose_landmarker_lite"])


class CameraSetOut(BaseModel):
    """A camera set: its id (for the batches and the end), the exercise and target, where it stands."""

    set_id: str = Field(examples=["3f2b8c1e-4d5a-4e6f-8a9b-0c1d2e3f4a5b"])
    patient_id: int = Field(examples=[12])
    plan_item_id: int | None = Field(examples=[41])
    exercise_slug: str = Field(examples=["squat"])
    target_reps: int = Field(examples=[10])
    angles: list[str] = Field(description="the exercise's defining angles", examples=[["knee_flexion_left"]])
    model: str = Field(examples=["pose_landmarker_lite"])
    status: Literal["recording", "stored", "failed"]
    n_frames: int = Field(examples=[0])
    last_seq: int = Field(description="the newest batch received (-1: none)", examples=[-1])
    session_id: int | None = Field(default=None, description="the stored session once the set ended")
    error: str | None = None
    failure: Literal["too_short", "not_storable"] | None = Field(
        default=None,
        description="why a failed set stored nothing: too few frames to analyse, or frames no session file may hold",
    )


class FrameIn(BaseModel):
    """One frame of the landmarker: its time and the 33 landmarks."""

    model_config = ConfigDict(extra="forbid")

    t: float = Field(description="seconds on the set's clock (0 at its start), increasing", examples=[0.033])
    world: Landmarks = Field(description="33 x [x, y, z] metres, the model's world frame (origin between the hips)")
    image: Landmarks = Field(description="33 x [x, y, z]: x, y normalised to the image (0..1), z relative depth")
    visibility: Annotated[list[float], Field(min_length=N_LANDMARKS, max_length=N_LANDMARKS)] = Field(
        description="33 values in 0..1: how likely each landmark is visible"
    )


class BatchIn(BaseModel):
    """A batch of frames of one set; seq counts the batches from 0, so a re-sent batch is recognised."""

    model_config = ConfigDict(extra="forbid")

    seq: int = Field(ge=0, le=10**6, examples=[0])
    version: Literal[1] = Field(description="the landmark wire contract's version (kinect_agent.sources.webcam)")
    image_size: Annotated[list[int], Field(min_length=2, max_length=2)] = Field(
        description="[width, height] of the analysed picture, pixels (16..8192)", examples=[[640, 480]]
    )
    frames: list[FrameIn] = Field(min_length=1, max_length=MAX_FRAMES_PER_BATCH)
    fps: float | None = Field(default=None, ge=0, le=240, description="the page's landmarker rate now (frames/s)")


class BatchOut(BaseModel):
    """What the server made of the frames so far: the live count and plain-words advice."""

    set_id: str = Field(examples=["3f2b8c1e-4d5a-4e6f-8a9b-0c1d2e3f4a5b"])
    seq: int = Field(description="the batch this answers", examples=[12])
    repeated: bool = Field(description="this batch had been received before (nothing new stored)")
    last_seq: int
    n_frames: int
    count: int = Field(description="repetitions so far (the online filter's live count)", examples=[3])
    target: int = Field(examples=[10])
    angle_name: str | None = None
    angle_deg: float | None = None
    hint: str | None = None
    still_s: float = Field(default=0.0, description="seconds without movement of the defining angle")


class EndIn(BaseModel):
    """The end of a set: the last batch the page sent, and why it ended."""

    model_config = ConfigDict(extra="forbid")

    last_seq: int = Field(ge=-1, le=10**6, description="the newest batch the page sent (-1: none)", examples=[41])
    reason: Literal["target", "stop", "still", "limit", "error"] = Field(default="stop", examples=["target"])
