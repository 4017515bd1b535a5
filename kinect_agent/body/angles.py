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
    shoulder_rotation_L/R  forearm WRI-ELB about the upper arm axis, from the forward direction towards up:
                           0 forearm pointing forward, +90 pointing up (external rotation with abducted arm),
                           -90 down; defined only when the elbow is bent; NaN while the upper arm hangs within
                           ROTATION_MIN_ELEVATION_DEG of straight down (there "up" does not tell the sign)
    hip_flexion_L/R     thigh KNE-HIP in the sagittal plane: atan2(fwd, -up); 90 seated
    hip_abduction_L/R   thigh out of the sagittal plane: arcsin(thigh (unit) . out); the frontal-plane angle
                        atan2(out, -up) while the thigh moves in that plane, but, unlike it, blind to hip flexion
    trunk_flexion       angle between NECK-ROOT and the world vertical +y; 0 upright
    trunk_lateral_flexion  tilt of the trunk towards the subject's left hip (+) or right hip (−):
                           arcsin of NECK-ROOT (unit) along the HIP_R->HIP_L direction

Domains (DOMAIN_DEG): every angle lies in the interval its definition allows; the planar angles (atan2) are wrapped
into [seam, seam + 360): the sagittal ones (shoulder and hip flexion) at SAGITTAL_SEAM_DEG, −100° (the limb pointing
backwards 10° above the horizontal, in the trunk's frame), the shoulder abduction at PLANAR_SEAM_DEG, −120°; so an arm
overhead reads 180° ± its sway, and an arm overhead while the trunk leans forward (a deep squat: 200-250° on the
Kinect) or a thigh mistracked over the top stays on one side of the seam. Nothing downstream unwraps (series), so a
smoothed or percentile value stays in the domain too. A planar angle is NaN in a frame where
its limb lies more than 60° out of the angle's plane (the in-plane part below PLANE_MIN_FRACTION of the limb's
length). Why each rule: bench/README.md, "Clinical angles: why each convention".
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


PLANAR_SEAM_DEG = -120.0  # the shoulder abduction's seam: the arm across the body, 30° above the horizontal
SAGITTAL_SEAM_DEG = -100.0  # the shoulder and hip flexion's seam: the limb backwards, 10° above the horizontal
ROTATION_MIN_ELEVATION_DEG = 30.0  # shoulder rotation is undefined below this elevation of the upper arm
PLANE_MIN_FRACTION = 0.5  # a planar angle needs this much of its limb in its plane (within 60° of it)
_PLANAR = (PLANAR_SEAM_DEG, PLANAR_SEAM_DEG + 360.0)
_SAGITTAL = (SAGITTAL_SEAM_DEG, SAGITTAL_SEAM_DEG + 360.0)
# (low, high) degrees each angle can take by its definition (high excluded for the planar angles).
DOMAIN_DEG: dict[str, tuple[float, float]] = {
    **{f"{n}_{s}": (0.0, 180.0) for n in ("elbow_flexion", "knee_flexion") for s in "LR"},
    **{f"{n}_{s}": _SAGITTAL for n in ("shoulder_flexion", "hip_flexion") for s in "LR"},
    **{f"shoulder_abduction_{s}": _PLANAR for s in "LR"},
    **{f"shoulder_rotation_{s}": (-180.0, 180.0) for s in "LR"},
    **{f"hip_abduction_{s}": (-90.0, 90.0) for s in "LR"},
    "trunk_flexion": (0.0, 180.0),
    "trunk_lateral_flexion": (-90.0, 90.0),
}


def in_domain(name: str, deg: np.ndarray, tol: float = 1e-6) -> np.ndarray:
    """Returns (...,) bool: where deg (degrees) lies in DOMAIN_DEG[name] (NaN counts as inside: undefined)."""
    lo, hi = DOMAIN_DEG[name]
    deg = np.asarray(deg, dtype=np.float64)
    return ~((deg < lo - tol) | (deg > hi + tol))


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Returns (...,) the sum of a * b over the last axis (3; a, b broadcast), added in the order np.sum adds a
    contiguous axis, ((0 + a0 b0) + a1 b1) + a2 b2: the same numbers, without a reduction over 3 values per row
    (most of the angle SDs' time)."""
    return ((0.0 + a[..., 0] * b[..., 0]) + a[..., 1] * b[..., 1]) + a[..., 2] * b[..., 2]


def _unit(v: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return v / np.sqrt(_dot(v, v))[..., None]


def _joint(positions: np.ndarray, name: str) -> np.ndarray:
    return positions[..., INDEX[name], :]


def body_frame(positions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Returns (up, left, forward) unit vectors, each (..., 3), of the trunk frame defined above."""
    up = _unit(_joint(positions, "NECK") - _joint(positions, "ROOT"))
    across = _joint(positions, "SHO_L") - _joint(positions, "SHO_R")
    hips = _joint(positions, "HIP_L") - _joint(positions, "HIP_R")
    across = np.where(np.isfinite(across), across, hips)
    left = _unit(across - _dot(across, up)[..., None] * up)
    forward = np.cross(left, up)
    return up, left, forward


def _inner_angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle in degrees between vectors a and b, each (..., 3)."""
    cos = _dot(_unit(a), _unit(b))
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def _plane_angle(v: np.ndarray, up: np.ndarray, axis: np.ndarray, seam: float, mask: bool = True) -> np.ndarray:
    """Angle in degrees of v projected on the plane (−up, axis): 0 along −up, +90 along axis, wrapped into
    [seam, seam + 360); with mask, NaN where less than PLANE_MIN_FRACTION of v lies in that plane."""
    down = -_dot(v, up) + 0.0  # + 0.0 turns -0.0 into 0.0 so atan2(0, 0) reads 0, not 180
    along = _dot(v, axis)
    deg = np.degrees(np.arctan2(along, down))
    deg = seam + np.mod(deg - seam, 360.0)
    if not mask:
        return deg
    with np.errstate(invalid="ignore"):
        off_plane = np.hypot(down, along) < PLANE_MIN_FRACTION * np.sqrt(_dot(v, v))
    return np.where(off_plane, np.nan, deg)


def _out_of_plane(v: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Angle in degrees between v and the plane whose unit normal is `normal`, signed towards it: [−90, 90]."""
    return np.degrees(np.arcsin(np.clip(_dot(_unit(v), normal), -1.0, 1.0)))


def joint_angles(positions: np.ndarray, *, mask_off_plane: bool = True) -> dict[str, np.ndarray]:
    """Returns every angle of ANGLE_NAMES, each (...,) degrees in its DOMAIN_DEG (NaN: undefined or untracked),
    for positions (..., J, 3) m.

    mask_off_plane=False keeps the planar angles where their limb is out of their plane (the repetition counter's
    continuous signal, analysis.angles.counting_angles; not a clinical number)."""
    p = np.asarray(positions, dtype=np.float64)
    m = mask_off_plane
    up, left, forward = body_frame(p)
    out: dict[str, np.ndarray] = {}
    for side, outward in (("L", left), ("R", -left)):
        sho, elb, wri = (_joint(p, f"{n}_{side}") for n in ("SHO", "ELB", "WRI"))
        hip, kne, ank = (_joint(p, f"{n}_{side}") for n in ("HIP", "KNE", "ANK"))
        upper, fore, thigh = elb - sho, wri - elb, kne - hip
        out[f"elbow_flexion_{side}"] = 180.0 - _inner_angle(sho - elb, wri - elb)
        out[f"knee_flexion_{side}"] = 180.0 - _inner_angle(hip - kne, ank - kne)
        out[f"shoulder_flexion_{side}"] = _plane_angle(upper, up, forward, SAGITTAL_SEAM_DEG, m)
        out[f"shoulder_abduction_{side}"] = _plane_angle(upper, up, outward, PLANAR_SEAM_DEG, m)
        rotation = _rotation_about(upper, fore, forward, up)
        with np.errstate(invalid="ignore"):
            hanging = -_dot(_unit(upper), up) > np.cos(np.radians(ROTATION_MIN_ELEVATION_DEG))
        out[f"shoulder_rotation_{side}"] = np.where(hanging, np.nan, rotation)
        out[f"hip_flexion_{side}"] = _plane_angle(thigh, up, forward, SAGITTAL_SEAM_DEG, m)
        out[f"hip_abduction_{side}"] = _out_of_plane(thigh, outward)
    trunk = _unit(_joint(p, "NECK") - _joint(p, "ROOT"))
    vertical = np.array([0.0, 1.0, 0.0])
    out["trunk_flexion"] = _inner_angle(trunk, np.broadcast_to(vertical, trunk.shape))
    hips_left = _unit(_joint(p, "HIP_L") - _joint(p, "HIP_R"))
    out["trunk_lateral_flexion"] = np.degrees(np.arcsin(np.clip(_dot(trunk, hips_left), -1.0, 1.0)))
    return {name: out[name] for name in ANGLE_NAMES}


def _rotation_about(axis_vec: np.ndarray, v: np.ndarray, ref: np.ndarray, up: np.ndarray) -> np.ndarray:
    """Signed angle in degrees of v about axis_vec, from ref (projected) towards up (projected)."""
    a = _unit(axis_vec)

    def project(x: np.ndarray) -> np.ndarray:
        return _unit(x - _dot(x, a)[..., None] * a)

    v_p, ref_p = project(v), project(ref)
    other = np.cross(a, ref_p)
    # Orient `other` so it leans towards up; otherwise the sign would flip between arms.
    flip = np.sign(_dot(other, up))[..., None]
    other = other * np.where(flip == 0, 1.0, flip)
    return np.degrees(np.arctan2(_dot(v_p, other), _dot(v_p, ref_p)))
