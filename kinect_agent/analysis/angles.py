"""The angles the analysis measures, and those it counts repetitions on.

Measured angles (measured_angles): the agent's clinical angles (kinect_agent.body.angles.joint_angles, each
in its DOMAIN_DEG) of the positions gap-filled and smoothed by series.smooth_positions. They are the one
definition behind every number of a session: range of motion and its intervals, the key numbers, the curves of
the session page and the exported angle tables.

Counting angles (counting_angles): the measured angles, except the hip angles, which the counter reads as the thigh's
elevation (signed), and the shoulder abduction, which it reads folded (folded_abduction). On real Kinect data the legs
are mistracked at the top of a high knee lift (UI-PRMD hurdle step and leg raise: the thigh reads as pointing up and
backwards for a few frames) and the sagittal projection then jumps, splitting or hiding repetitions. The elevation is
the 3-D angle between the thigh HIP→KNE and the trunk's down direction (−up of angles.body_frame), in [0, 180] degrees
and continuous; it equals |hip flexion| (|hip abduction|) while the thigh moves in the sagittal (frontal) plane. Its
sign is the sign of the measured angle's median over the frames where the thigh is raised more than 20°. The counter's
signal only: the repetitions' peaks are reported on the measured angles (kinect_agent.analysis.report.measured_peak).
On the webcam an arm raised out to the side may come down in front of the body (the musicalgestures dancer's left arm
on the full pose model): its projection on the frontal plane shrinks and turns through the inner side, the
frontal-plane angle crosses its seam (−120/240 degrees: 225 to −118 on that clip) and the raises merge; the folded
abduction equals |shoulder abduction| while the arm moves in the frontal plane and stays continuous where it points
forward or back (its forward part read at FORWARD_WEIGHT; the elevation, weight 1, would count the hanging arm's
forward sway: the webcam's still-standing sets). The shoulder flexion stays planar: there the elevation would count
the idle arm's sideways drift (UI-PRMD shoulder extension), the plane does not; it is counted also where the arm is
out of its plane (joint_angles(mask_off_plane=False)), where the measured angle is undefined (why: bench/README.md,
"Clinical angles: why each convention"; the folded abduction: "The dancer's left shoulder across the planar seam").
"""

from __future__ import annotations

from dataclasses import dataclass

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
FORWARD_WEIGHT = 0.25  # the share of the arm's forward/backward part the counted shoulder abduction reads
_CONTINUOUS = ("shoulder_flexion",)  # counted on its planar angle, unmasked


@dataclass(frozen=True)
class Measured:
    """The positions a session is measured on and their clinical angles.

    positions: (T, J, 3) float, metres, camera frame, gap-filled and smoothed (series.smooth_positions); angles:
    {name: (T,) degrees} for every name of ANGLE_NAMES (joint_angles of those positions); up: (T, 3) the trunk's
    up direction (angles.body_frame)."""

    positions: np.ndarray
    angles: dict[str, np.ndarray]
    up: np.ndarray


def measured_angles(t: np.ndarray, positions: np.ndarray) -> Measured:
    """Returns the Measured angles of positions: (T, J, 3) m, camera frame, NaN = untracked, at times t: (T,) s."""
    smoothed = series.smooth_positions(t, positions)
    return Measured(smoothed, joint_angles(smoothed), body_frame(smoothed)[0])


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


def folded_abduction(positions: np.ndarray, side: str) -> np.ndarray:
    """Returns (T,) degrees in [0, 180]: the upper arm SHO→ELB of side "L" or "R" as the counter reads its abduction,
    atan2(hypot(out, FORWARD_WEIGHT * fwd), down) with out, fwd, down its parts along the trunk's outward, forward
    and down directions (angles.body_frame).

    It equals the frontal-plane abduction (0 hanging, 90 out to the side, 180 overhead) while the arm moves in that
    plane on the outward side, and its mirror (−abduction) across the body; it is continuous wherever the arm points
    (FORWARD_WEIGHT > 0: defined where the arm points forward or back, where the planar angle turns through its
    seam); FORWARD_WEIGHT = 1 would be the arm's elevation, which also reads the arm's forward sway at rest.
    positions: (T, J, 3) float, metres, camera frame, NaN = untracked (gives NaN).
    """
    up, left, forward = body_frame(positions)
    outward = left if side == "L" else -left
    arm = positions[:, INDEX[f"ELB_{side}"]] - positions[:, INDEX[f"SHO_{side}"]]
    along = np.hypot(series.dot3(arm, outward), FORWARD_WEIGHT * series.dot3(arm, forward))
    return np.degrees(np.arctan2(along, -series.dot3(arm, up)))


def counting_angles(
    positions: np.ndarray,
    names: tuple[str, ...],
    clinical: dict[str, np.ndarray] | None = None,
    up: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Returns {name: (T,) degrees} for the angles `names`: hip angles as signed thigh elevation, shoulder abduction
    folded (folded_abduction), shoulder flexion unmasked, others as is.

    positions: (T, J, 3) float, metres, camera frame, NaN = untracked. clinical: joint_angles(positions) when
    already computed; up: (T, 3) the trunk's up direction likewise. Raises ValueError on another shape or an
    unknown angle name.
    """
    positions = np.asarray(positions, dtype=np.float64)
    if positions.ndim != 3 or positions.shape[1:] != (len(INDEX), 3):
        raise ValueError(f"positions must have shape (T, {len(INDEX)}, 3), got {positions.shape}")
    clinical = joint_angles(positions) if clinical is None else clinical
    unknown = [name for name in names if name not in clinical]
    if unknown:
        raise ValueError(f"unknown angle {unknown[0]!r}; known angles: {', '.join(clinical)}")
    shoulders = [name for name in names if name.startswith(_CONTINUOUS)]
    continuous = joint_angles(positions, mask_off_plane=False) if shoulders else {}
    out: dict[str, np.ndarray] = {}
    for name in names:
        prefix, side = name[:-2], name[-1]
        if prefix == "shoulder_abduction":
            out[name] = folded_abduction(positions, side)
            continue
        if prefix not in _PLANAR_LIMBS:
            out[name] = continuous.get(name, clinical[name])
            continue
        proximal, distal = (f"{j}_{side}" for j in _PLANAR_LIMBS[prefix])
        elev = elevation(positions, proximal, distal, up)
        raised = np.isfinite(clinical[name]) & (elev > RAISED_DEG)
        sign = -1.0 if raised.any() and np.median(clinical[name][raised]) < 0 else 1.0
        out[name] = sign * elev
    return out
