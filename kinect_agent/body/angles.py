"""Clinical joint angles from joint positions, in degrees, with documented conventions.

All functions take positions: (..., J, 3) float, metres, any right-handed frame with y up
(camera frame); NaN where untracked, which gives NaN angles.

Body frame (per frame, from the trunk, independent of where the camera stands):
    up      = NECK - ROOT, normalised
    left    = SHO_L - SHO_R, made orthogonal to up, normalised (the subject's left)
    forward = left x up (points where the chest faces)

Conventions (0 = anatomical neutral, standing with arms hanging and legs straight):
    elbow_flexion_L/R   180 - angle(SHO-ELB, WRI-ELB); 0 straight, ~140 fully bent
    knee_flexion_L/R    180 - angle(HIP-KNE, ANK-KNE); 0 straight, 90 seated
    shoulder_flexion_L/R   upper arm ELB-SHO in the sagittal plane (up, forward): atan2(fwd, -up);
                           90 arm forward horizontal, 180 overhead, negative = extension
    shoulder_abduction_L/R upper arm in the frontal plane (up, outward side): atan2(out, -up);
                           90 arm out sideways, 180 overhead
    shoulder_rotation_L/R  forearm WRI-ELB about the upper arm axis, measured from the forward
                           direction towards up-in-body terms: 0 forearm pointing forward, +90 pointing
                           up (external rotation with abducted arm), -90 down; NaN-free only when
                           the elbow is bent
    hip_flexion_L/R     thigh KNE-HIP in the sagittal plane: atan2(fwd, -up); 90 seated
    hip_abduction_L/R   thigh in the frontal plane: atan2(out, -up)
    trunk_flexion       angle between NECK-ROOT and the world vertical +y; 0 upright
    trunk_lateral_flexion  tilt of the trunk towards the subject's left hip (+) or right hip (−):
                           arcsin of NECK-ROOT (unit) along the HIP_R->HIP_L direction
"""

from __future__ import annotations

import numpy as np

from kinect_agent.skeleton import INDEX

ANGLE_NAMES: tuple[str, ...] = (
    "elbow_flexion_L", "elbow_flexion_R", "knee_flexion_L", "knee_flexion_R",
    "shoulder_flexion_L", "shoulder_flexion_R", "shoulder_abduction_L", "shoulder_abduction_R",
    "shoulder_rotation_L", "shoulder_rotation_R",
    "hip_flexion_L", "hip_flexion_R", "hip_abduction_L", "hip_abduction_R",
    "trunk_flexion", "trunk_lateral_flexion",
)  # fmt: skip


def _unit(v: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _joint(positions: np.ndarray, name: str) -> np.ndarray:
    return positions[..., INDEX[name], :]


def body_frame(positions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Returns (up, left, forward) unit vectors, each (..., 3), of the trunk frame defined above."""
    up = _unit(_joint(positions, "NECK") - _joint(positions, "ROOT"))
    across = _joint(positions, "SHO_L") - _joint(positions, "SHO_R")
    hips = _joint(positions, "HIP_L") - _joint(positions, "HIP_R")
    across = np.where(np.isfinite(across), across, hips)
    left = _unit(across - np.sum(across * up, axis=-1, keepdims=True) * up)
    forward = np.cross(left, up)
    return up, left, forward


def _inner_angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle in degrees between vectors a and b, each (..., 3)."""
    cos = np.sum(_unit(a) * _unit(b), axis=-1)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def _plane_angle(v: np.ndarray, up: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Angle in degrees of v projected on the plane (−up, axis): 0 along −up, +90 along axis.

    Meaningful when v moves near that plane (the plane of the exercise); a limb pointing straight
    along the third axis projects to a point and reads 0.
    """
    down = -np.sum(v * up, axis=-1) + 0.0  # + 0.0 turns -0.0 into 0.0 so atan2(0, 0) reads 0, not 180
    return np.degrees(np.arctan2(np.sum(v * axis, axis=-1), down))


def joint_angles(positions: np.ndarray) -> dict[str, np.ndarray]:
    """Returns every angle of ANGLE_NAMES, each (...,) degrees, for positions (..., J, 3) m."""
    p = np.asarray(positions, dtype=np.float64)
    up, left, forward = body_frame(p)
    out: dict[str, np.ndarray] = {}
    for side, outward in (("L", left), ("R", -left)):
        sho, elb, wri = (_joint(p, f"{n}_{side}") for n in ("SHO", "ELB", "WRI"))
        hip, kne, ank = (_joint(p, f"{n}_{side}") for n in ("HIP", "KNE", "ANK"))
        upper, fore, thigh = elb - sho, wri - elb, kne - hip
        out[f"elbow_flexion_{side}"] = 180.0 - _inner_angle(sho - elb, wri - elb)
        out[f"knee_flexion_{side}"] = 180.0 - _inner_angle(hip - kne, ank - kne)
        out[f"shoulder_flexion_{side}"] = _plane_angle(upper, up, forward)
        out[f"shoulder_abduction_{side}"] = _plane_angle(upper, up, outward)
        out[f"shoulder_rotation_{side}"] = _rotation_about(upper, fore, forward, up)
        out[f"hip_flexion_{side}"] = _plane_angle(thigh, up, forward)
        out[f"hip_abduction_{side}"] = _plane_angle(thigh, up, outward)
    trunk = _unit(_joint(p, "NECK") - _joint(p, "ROOT"))
    vertical = np.array([0.0, 1.0, 0.0])
    out["trunk_flexion"] = _inner_angle(trunk, np.broadcast_to(vertical, trunk.shape))
    hips_left = _unit(_joint(p, "HIP_L") - _joint(p, "HIP_R"))
    out["trunk_lateral_flexion"] = np.degrees(np.arcsin(np.clip(np.sum(trunk * hips_left, axis=-1), -1.0, 1.0)))
    return {name: out[name] for name in ANGLE_NAMES}


def _rotation_about(axis_vec: np.ndarray, v: np.ndarray, ref: np.ndarray, up: np.ndarray) -> np.ndarray:
    """Signed angle in degrees of v about axis_vec, from ref (projected) towards up (projected)."""
    a = _unit(axis_vec)

    def project(x: np.ndarray) -> np.ndarray:
        return _unit(x - np.sum(x * a, axis=-1, keepdims=True) * a)

    v_p, ref_p = project(v), project(ref)
    other = np.cross(a, ref_p)
    # Orient `other` so it leans towards up; otherwise the sign would flip between arms.
    flip = np.sign(np.sum(other * up, axis=-1, keepdims=True))
    other = other * np.where(flip == 0, 1.0, flip)
    return np.degrees(np.arctan2(np.sum(v_p * other, axis=-1), np.sum(v_p * ref_p, axis=-1)))
