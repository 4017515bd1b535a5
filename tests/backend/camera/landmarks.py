"""Landmark frames for tests: a body of BlazePose's 33 landmarks standing or squatting, as the page sends them.

world: (33, 3) m, BlazePose's world frame (origin between the hips, x to the image's right, y down, z away from the
camera). image: (33, 3), x and y normalised to a 640 x 480 picture of a camera 2.5 m in front, z relative depth.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

THIGH_M = SHANK_M = 0.45
DEPTH_M = 2.5  # from the camera to the hips
FOCAL = 0.8  # focal length in image widths (about 64 degrees of view)
IMAGE_SIZE = [640, 480]


def body(knee_deg: float = 0.0) -> np.ndarray:
    """Returns world landmarks (33, 3) m of a person facing the camera, knees flexed by knee_deg (a squat)."""
    phi = math.radians(knee_deg) * 0.5  # thigh forward from vertical; the shank leans back by the same
    w = np.zeros((33, 3))
    head = {0: (0.0, -0.72, -0.08), 1: (0.03, -0.75, -0.07), 2: (0.035, -0.75, -0.07), 3: (0.04, -0.75, -0.07),
            4: (-0.03, -0.75, -0.07), 5: (-0.035, -0.75, -0.07), 6: (-0.04, -0.75, -0.07), 7: (0.07, -0.73, 0.0),
            8: (-0.07, -0.73, 0.0), 9: (0.02, -0.68, -0.07), 10: (-0.02, -0.68, -0.07)}  # fmt: skip
    for i, p in head.items():
        w[i] = p
    for side, x in ((0, 0.1), (1, -0.1)):  # 0: left (odd landmarks 11.., 23..), 1: right
        s = 1 if side == 0 else -1
        w[11 + side] = (s * 0.18, -0.5, 0.0)
        w[13 + side] = (s * 0.2, -0.22, 0.0)
        w[15 + side] = (s * 0.2, 0.02, 0.0)
        for k, dy in ((17, 0.08), (19, 0.09), (21, 0.05)):
            w[k + side] = (s * 0.21, 0.02 + dy, -0.02)
        hip = np.array([x, 0.0, 0.0])
        knee = hip + THIGH_M * np.array([0.0, math.cos(phi), -math.sin(phi)])
        ankle = knee + SHANK_M * np.array([0.0, math.cos(phi), math.sin(phi)])
        w[23 + side], w[25 + side], w[27 + side] = hip, knee, ankle
        w[29 + side] = ankle + (0.0, 0.04, 0.05)
        w[31 + side] = ankle + (0.0, 0.05, -0.14)
    return w


def image_of(world: np.ndarray) -> np.ndarray:
    """Returns image landmarks (33, 3) of world landmarks seen by a camera DEPTH_M in front of the hips."""
    z = DEPTH_M + world[:, 2]
    x = 0.5 + FOCAL * world[:, 0] / z
    y = 0.5 + FOCAL * (4 / 3) * world[:, 1] / z
    return np.stack([x, y, world[:, 2] - world[23:25, 2].mean()], axis=1)


def frame(t: float, knee_deg: float = 0.0, visibility: float = 0.95) -> dict[str, Any]:
    """Returns one frame as the page sends it (JSON-ready)."""
    w = body(knee_deg)
    return {"t": round(t, 4), "world": w.round(5).tolist(), "image": image_of(w).round(5).tolist(),
            "visibility": [visibility] * 33}  # fmt: skip


def squats(
    reps: int,
    *,
    fps: float = 30.0,
    period_s: float = 2.5,
    rest_s: float = 1.5,
    t0: float = 0.0,
    depth_deg: float = 90.0,
) -> list[Any]:
    """Returns the frames of `reps` squats to depth_deg of knee flexion with rest_s of standing before and after."""
    n = int(round((2 * rest_s + reps * period_s) * fps))
    out = []
    for k in range(n):
        t = k / fps
        u = t - rest_s
        knee = 0.5 * depth_deg * (1 - math.cos(2 * math.pi * u / period_s)) if 0 <= u <= reps * period_s else 0.0
        out.append(frame(t0 + t, knee))
    return out


def batch(seq: int, frames: list[Any]) -> dict[str, Any]:
    """Returns a batch body of the frames as the page sends it."""
    return {"seq": seq, "version": 1, "image_size": IMAGE_SIZE, "frames": frames}
