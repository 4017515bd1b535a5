"""How an exercise looks: one repetition of the simulator's motion library (kinect_agent.sources.motions), seen
from the side (movements in the sagittal plane) or the front (frontal plane), for the patient page's looping figure.

The movement is the simulator's exact recording (simulate_truth: forward kinematics of the paper's chain, no sensor
noise), so the figure moves as the exercise is counted. Frames are projected to 2D in metres:
    front: (x, y) of the camera frame, the subject facing the viewer as in a mirror (their left on the left);
    side:  (-z, y), the subject facing right.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Annotated

import numpy as np
from pydantic import BaseModel, Field

from kinect_agent import skeleton
from kinect_agent.sources.motions import SPECS
from kinect_agent.sources.simulator import simulate_truth

RATE_HZ = 15.0  # frames per second of the demonstration (smooth enough for a drawn figure, small to send)
SIDE_PLANES = {"sagittal", "transverse"}


class DemonstrationOut(BaseModel):
    """One repetition of an exercise as 2D joint positions over time."""

    slug: str = Field(examples=["elbow_flexion"])
    view: str = Field(description="front or side", examples=["side"])
    rate_hz: float = Field(description="frames per second", examples=[RATE_HZ])
    joints: list[str] = Field(description="joint names, the order of each frame", examples=[["ROOT", "SPINE"]])
    bones: list[Annotated[list[int], Field(min_length=2, max_length=2)]] = Field(
        description="(parent, child) joint indices to draw", examples=[[[0, 1]]]
    )
    frames: list[list[Annotated[list[float], Field(min_length=2, max_length=2)]]] = Field(
        description="(T, J, 2) metres: horizontal, up; the first frame's lowest joint at 0; empty when the motion "
        "library has no movement for the exercise (the page then shows the written instructions only)"
    )


def view_for(plane: str) -> str:
    """Returns the view that shows a movement in `plane` best: "side" (sagittal, transverse) or "front"."""
    return "side" if plane in SIDE_PLANES else "front"


@lru_cache(maxsize=32)
def demonstration(slug: str, view: str, pose: str | None = None) -> DemonstrationOut:
    """Returns one repetition of the exercise `slug` seen from `view`, done in `pose` ("standing", "sitting") when
    the motion allows it (no frames when the motion library has no movement for the exercise)."""
    joints, bones = list(skeleton.JOINTS), [[int(a), int(b)] for a, b in skeleton.BONES]
    if slug not in SPECS:
        return DemonstrationOut(slug=slug, view=view, rate_hz=RATE_HZ, joints=joints, bones=bones, frames=[])
    pose = pose if pose in SPECS[slug].poses else None  # the library's pose (sitting), else the motion's own
    rec = simulate_truth(slug, 1, pose=pose, seed=0, rate_hz=RATE_HZ)
    p = rec.positions  # (T, J, 3) metres, camera frame, subject facing the camera
    horizontal = p[:, :, 0] if view == "front" else -p[:, :, 2]
    xy = np.stack([horizontal, p[:, :, 1]], axis=-1)  # (T, J, 2)
    xy = xy - np.array([xy[0, :, 0].mean(), xy[0, :, 1].min()])
    return DemonstrationOut(
        slug=slug,
        view=view,
        rate_hz=RATE_HZ,
        joints=joints,
        bones=bones,
        frames=np.round(xy, 3).tolist(),
    )
