"""Data quality of a session: how much was tracked, how much was thrown away as outliers, and whether to trust it.

Definitions (joints = the joints the exercise's defining angles use, else all 20):
    tracked_fraction  = fraction of (frame, joint) samples of those joints present in the raw recording (state 1
                        or 2), in [0, 1];
    outlier_fraction  = fraction of the present samples of those joints that lie more than OUTLIER_M (0.15 m)
                        from the measured (filtered) position; 0 when the measurement is the raw recording;
    ok                = every check passes; `reasons` lists the failed checks in words:
                        at least MIN_FRAMES frames and MIN_DURATION_S seconds, tracked_fraction ≥ MIN_TRACKED,
                        outlier_fraction ≤ MAX_OUTLIERS, and the measured positions of those joints are finite.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from kinect_agent.analysis import reasons as why
from kinect_agent.analysis import series
from kinect_agent.recording import Recording
from kinect_agent.skeleton import INDEX, JOINTS, NOT_TRACKED

OUTLIER_M = 0.15
MIN_FRAMES = 30
MIN_DURATION_S = 2.0
MIN_TRACKED = 0.8
MAX_OUTLIERS = 0.1

# joints each clinical angle is computed from (angles.body_frame uses ROOT, NECK and the shoulders)
_TRUNK = ("ROOT", "NECK", "SHO_L", "SHO_R")
_ANGLE_JOINTS = {
    "elbow_flexion": ("SHO", "ELB", "WRI"),
    "knee_flexion": ("HIP", "KNE", "ANK"),
    "shoulder_flexion": ("SHO", "ELB"),
    "shoulder_abduction": ("SHO", "ELB"),
    "shoulder_rotation": ("SHO", "ELB", "WRI"),
    "hip_flexion": ("HIP", "KNE"),
    "hip_abduction": ("HIP", "KNE"),
}


def angle_joints(names: tuple[str, ...]) -> list[int]:
    """Returns the sorted joint indices the angles `names` depend on (all joints when names is empty)."""
    if not names:
        return list(range(len(JOINTS)))
    joints = set(_TRUNK)
    for name in names:
        prefix, side = name[:-2], name[-1]
        joints.update(f"{j}_{side}" for j in _ANGLE_JOINTS.get(prefix, ()))
        if prefix.startswith("trunk"):
            joints.update(("HIP_L", "HIP_R"))
    return sorted(INDEX[j] for j in joints)


def tracked_fraction(raw: Recording, angle_names: tuple[str, ...] = ()) -> float:
    """Returns the fraction of the (frame, joint) samples of the joints of angle_names (angle_joints) that the
    camera tracked (state 1 or 2), in [0, 1]; 0 for an empty recording."""
    present = raw.state[:, angle_joints(angle_names)] != NOT_TRACKED
    return float(present.mean()) if present.size else 0.0


def assess(raw: Recording, measured: np.ndarray | None, angle_names: tuple[str, ...] = ()) -> dict[str, Any]:
    """Returns {"ok", "tracked_fraction", "outlier_fraction", "reasons"} for a session.

    raw: the recording as captured. measured: (T, J, 3) metres, camera frame, the positions the metrics use
    (the filtered recording), or None when the metrics use the raw recording.
    """
    joints = angle_joints(angle_names)
    present = raw.state[:, joints] != NOT_TRACKED
    tracked = tracked_fraction(raw, angle_names)
    outliers = 0.0
    finite = True
    if measured is not None:
        if measured.shape != raw.positions.shape:
            raise ValueError(f"measured must have shape {raw.positions.shape}, got {measured.shape}")
        sub = measured[:, joints]
        finite = bool(np.all(np.isfinite(sub)))
        dist = series.norm3(raw.positions[:, joints] - sub)
        far = present & (np.nan_to_num(dist, nan=np.inf) > OUTLIER_M)
        outliers = float(far.sum() / present.sum()) if present.any() else 0.0
    reasons = []  # ids and numbers, as the document stores them (backend.session_texts.reasons writes them out)
    if raw.n_frames < MIN_FRAMES:
        reasons.append(why.TOO_FEW_FRAMES.reason(frames=raw.n_frames, needed=MIN_FRAMES))
    if raw.duration < MIN_DURATION_S:
        reasons.append(why.TOO_SHORT.reason(seconds=raw.duration, needed=MIN_DURATION_S))
    if tracked < MIN_TRACKED:
        reasons.append(why.TOO_LITTLE_TRACKED.reason(tracked=tracked, needed=MIN_TRACKED))
    if outliers > MAX_OUTLIERS:
        reasons.append(why.TOO_MANY_ERRORS.reason(errors=outliers, allowed=MAX_OUTLIERS))
    if not finite:
        reasons.append(why.GAPS.reason())
    return {
        "ok": not reasons,
        "tracked_fraction": round(tracked, 4),
        "outlier_fraction": round(outliers, 4),
        "reasons": reasons,
    }
