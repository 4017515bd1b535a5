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
# Sagittal movements are seen from the side; frontal ones, and the transverse shoulder rotation (done with the arm
# held out to the side: from the side its upper arm points at the viewer and the raised forearm hides in the trunk),
# from the front.
SIDE_PLANES = {"sagittal"}


SEAT_BELOW_HIPS_M = 0.08  # the seat's top under the hip joints (half a thigh's thickness)
SEAT_BEHIND_HIPS_M = 0.12  # side view: the seat's back edge behind the hips
SEAT_BEFORE_KNEES_M = 0.06  # side view: the seat's front edge short of the knees
SEAT_BESIDE_HIPS_M = 0.14  # front view: the seat's edges beyond each hip


class SeatOut(BaseModel):
    """The chair a seated exercise is done on, in the frames' 2D metres: the seat's top at `height` from x0 to x1
    (side view: x0 its back edge, where the backrest rises; front view: its left and right edges)."""

    height: float = Field(description="metres above the floor", examples=[0.45])
    x0: float = Field(description="metres, horizontal", examples=[-0.2])
    x1: float = Field(description="metres, horizontal", examples=[0.25])


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
    seat: SeatOut | None = Field(default=None, description="the chair of an exercise done seated (where the first "
                                 "frame sits); null when standing")  # fmt: skip


def view_for(plane: str) -> str:
    """Returns the view that shows a movement in `plane` best: "side" (sagittal) or "front" (frontal, transverse)."""
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
        seat=seat_under(xy[0], view) if (pose or SPECS[slug].poses[0]) == "sitting" else None,
    )


def seat_under(frame: np.ndarray, view: str) -> SeatOut:
    """Returns the seat under a seated figure's frame: (J, 2) metres (horizontal, up), seen from `view`."""
    at = skeleton.INDEX
    hips = frame[[at["HIP_L"], at["HIP_R"]]]  # (2, 2)
    height = float(hips[:, 1].mean()) - SEAT_BELOW_HIPS_M
    if view == "side":  # the figure faces +x: the seat runs from behind the hips to short of the knees
        knees = frame[[at["KNE_L"], at["KNE_R"]], 0].mean()
        x0, x1 = float(hips[:, 0].mean()) - SEAT_BEHIND_HIPS_M, float(knees) - SEAT_BEFORE_KNEES_M
    else:
        x0, x1 = float(hips[:, 0].min()) - SEAT_BESIDE_HIPS_M, float(hips[:, 0].max()) + SEAT_BESIDE_HIPS_M
    return SeatOut(height=round(height, 3), x0=round(x0, 3), x1=round(x1, 3))
