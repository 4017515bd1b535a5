"""Angles the analysis counts repetitions on: the agent's clinical angles, with the hip's planar angles made robust.

The agent's hip_flexion and hip_abduction (kinect_agent.body.angles) project the thigh on one anatomical
plane. On real Kinect data the legs are mistracked at the top of a high knee lift (UI-PRMD hurdle step and leg
raise: the thigh reads as pointing up and backwards for a few frames) and the projection then jumps by 150-250°,
splitting or hiding repetitions. For the hip angles the analysis counts instead the thigh's elevation: the 3-D
angle between the thigh HIP→KNE and the trunk's down direction (−up of angles.body_frame), in [0, 180] degrees and
continuous; it equals |planar angle| while the thigh moves in its plane. Its sign is the sign of the planar
angle's median over the frames where the thigh is raised more than 20°. The shoulder angles stay planar: there
the elevation would count the idle arm's sideways drift (UI-PRMD shoulder extension), the plane does not.
"""

from __future__ import annotations

import numpy as np

from kinect_agent.analysis import series
from kinect_agent.body.angles import body_frame, joint_angles
from kinect_agent.skeleton import INDEX

# planar angle prefix -> (proximal joint, distal joint) of the limb it measures
_PLANAR_LIMBS = {
    "hip_flexion": ("HIP", "KNE"),
    "hip_abduction": ("HIP", "KNE"),
}
RAISED_DEG = 20.0


def elevation(positions: np.ndarray, proximal: str, distal: str, up: np.ndarray | None = None) -> np.ndarray:
    """Returns (T,) degrees: angle between the limb proximal→distal and the trunk's down direction.

    positions: (T, J, 3) float, metres, camera frame, NaN = untracked (gives NaN). up: (T, 3) the trunk's up
    (angles.body_frame) when already computed.
    """
    up = body_frame(positions)[0] if up is None else up
    limb = positions[:, INDEX[distal]] - positions[:, INDEX[proximal]]
    with np.errstate(invalid="ignore", divide="ignore"):
        cos = -series.dot3(limb, up) / series.norm3(limb)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def counting_angles(
    positions: np.ndarray,
    names: tuple[str, ...],
    clinical: dict[str, np.ndarray] | None = None,
    up: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Returns {name: (T,) degrees} for the angles `names`: hip angles as signed thigh elevation, others as is.

    positions: (T, J, 3) float, metres, camera frame, NaN = untracked. clinical: joint_angles(positions) when
    already computed; up: (T, 3) the trunk's up direction likewise. Raises ValueError on another shape or an
    unknown angle name.
    """
    positions = np.asarray(positions, dtype=np.float64)
    if positions.ndim != 3 or positions.shape[1:] != (len(INDEX), 3):
        raise ValueError(f"positions must have shape (T, {len(INDEX)}, 3), got {positions.shape}")
    clinical = joint_angles(positions) if clinical is None else clinical
    out: dict[str, np.ndarray] = {}
    for name in names:
        if name not in clinical:
            raise ValueError(f"unknown angle {name!r}; known angles: {', '.join(clinical)}")
        prefix, side = name[:-2], name[-1]
        if prefix not in _PLANAR_LIMBS:
            out[name] = clinical[name]
            continue
        proximal, distal = (f"{j}_{side}" for j in _PLANAR_LIMBS[prefix])
        elev = elevation(positions, proximal, distal, up)
        raised = np.isfinite(clinical[name]) & (elev > RAISED_DEG)
        sign = -1.0 if raised.any() and np.median(clinical[name][raised]) < 0 else 1.0
        out[name] = sign * elev
    return out
