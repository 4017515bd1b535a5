"""Kinect's systematic per-joint offset against mocap joint centres, in the body frame, and its removal.

The Kinect places some joints consistently away from the anatomical joint centres (its shoulder point sits above
and in front of the gleno-humeral centre, for instance). No filter removes that: it is the same in every frame.
This model stores one offset vector per joint (optionally per pose) in the body frame, learned from simultaneous
Kinect + mocap pairs (bench/offset_model.py), and subtracts it, rotated into the camera frame by each frame's body
frame:

    corrected[t, j] = positions[t, j] - R_cam_body[t] @ offset[pose[t], j]

Body frame (kinect_agent.body.angles.body_frame, from the trunk of the same frame): columns of R_cam_body are
x = the subject's left, y = up (ROOT -> NECK), z = forward (where the chest faces); right-handed.
Poses: "standing" or "bent" (mean knee flexion > BENT_KNEE_DEG: sitting, kneeling, deep squat).
Offsets are defined up to the rigid registration of mocap to Kinect used to measure them (a shift common to all
joints is not observable without a shared calibration, and changes no angle); joints without data have 0.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from kinect_agent import skeleton
from kinect_agent.body.angles import body_frame, joint_angles

POSES: tuple[str, ...] = ("standing", "bent")
BENT_KNEE_DEG = 60.0
MIN_FRAMES = 10  # a trial contributes a joint's (pose's) offset only with at least this many frames


@dataclass(frozen=True)
class OffsetModel:
    """offsets_m: pose -> (J, 3) float, metres, body frame (left, up, forward), Kinect minus mocap; a model with
    the single pose "all" applies to every frame. provenance: which data and date fitted it."""

    offsets_m: dict[str, np.ndarray]
    provenance: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        for pose, off in self.offsets_m.items():
            if pose not in (*POSES, "all"):
                raise ValueError(f"unknown pose {pose!r}; expected one of {(*POSES, 'all')}")
            if np.shape(off) != (skeleton.J, 3):
                raise ValueError(f"offsets of pose {pose!r}: expected shape ({skeleton.J}, 3), got {np.shape(off)}")

    @property
    def per_pose(self) -> bool:
        """True when the offsets depend on each frame's pose (no "all" entry)."""
        return "all" not in self.offsets_m

    def offsets_per_frame(self, positions: np.ndarray) -> np.ndarray:
        """Returns (T, J, 3) m, body frame: each frame's offsets (by its pose). positions: (T, J, 3) m."""
        if not self.per_pose:
            return np.broadcast_to(self.offsets_m["all"], positions.shape).copy()
        pose = pose_of(positions)
        table = np.stack([self.offsets_m.get(p, np.zeros((skeleton.J, 3))) for p in POSES])  # (P, J, 3)
        return table[pose]

    def apply(self, positions: np.ndarray) -> np.ndarray:
        """Returns positions minus the offsets rotated into the camera frame by each frame's body frame.

        positions: (T, J, 3) float, metres, camera frame (every joint filled, e.g. the pipeline's output).
        returns: (T, J, 3) float, metres, camera frame. A frame whose body frame is undefined is left unchanged.
        """
        p = np.asarray(positions, dtype=np.float64)
        if p.ndim != 3 or p.shape[1:] != (skeleton.J, 3):
            raise ValueError(f"positions: expected shape (T, {skeleton.J}, 3), got {p.shape}")
        shift = np.einsum("tab,tjb->tja", body_rotation(p), self.offsets_per_frame(p))
        return p - np.nan_to_num(shift, nan=0.0)


def body_rotation(positions: np.ndarray) -> np.ndarray:
    """Returns R_cam_body (..., 3, 3): columns left, up, forward of the body frame. positions: (..., J, 3) m."""
    up, left, forward = body_frame(positions)
    return np.stack([left, up, forward], axis=-1)


def to_body(vectors: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """Returns vectors (T, J, 3) camera frame expressed in the body frame of positions (T, J, 3): R^T v."""
    return np.einsum("tba,tjb->tja", body_rotation(positions), vectors)


def pose_of(positions: np.ndarray) -> np.ndarray:
    """Returns (T,) int index into POSES: 1 ("bent") where the mean knee flexion exceeds BENT_KNEE_DEG."""
    a = joint_angles(positions)
    knees = np.stack([a["knee_flexion_L"], a["knee_flexion_R"]])  # (2, T) degrees, NaN = unknown
    n = np.isfinite(knees).sum(axis=0)
    knee = np.nansum(knees, axis=0) / np.maximum(n, 1)
    return ((n > 0) & (knee > BENT_KNEE_DEG)).astype(np.int64)


def trial_offsets(estimate: np.ndarray, truth: np.ndarray, per_pose: bool = False) -> dict[str, np.ndarray]:
    """Returns pose -> (J, 3) m body frame: the component-wise median over frames of estimate - truth (robust to
    tracking-loss stretches); NaN for a joint with fewer than MIN_FRAMES finite frames in that pose.

    estimate, truth: (T, J, 3) float, metres, same camera frame, NaN = unknown (truth NaN = not scored)."""
    d = to_body(estimate - truth, estimate)
    if not per_pose:
        return {"all": _median(d)}
    pose = pose_of(estimate)
    return {p: _median(d[pose == k]) for k, p in enumerate(POSES)}


def _median(d: np.ndarray) -> np.ndarray:
    ok = np.all(np.isfinite(d), axis=-1)  # (T, J)
    out = np.full((skeleton.J, 3), np.nan)
    for j in np.flatnonzero(ok.sum(axis=0) >= MIN_FRAMES):
        out[j] = np.median(d[ok[:, j], j], axis=0)
    return out


def fit(
    pairs: Sequence[tuple[np.ndarray, np.ndarray]], per_pose: bool = False, provenance: dict | None = None
) -> OffsetModel:
    """Fits the model: per joint (and pose), the mean over trials of each trial's median body-frame offset, so each
    trial weighs the same; joints no trial measured get 0. pairs: (estimate, truth) per trial, as trial_offsets."""
    per_trial = [trial_offsets(e, t, per_pose) for e, t in pairs]
    poses = POSES if per_pose else ("all",)
    offsets = {}
    for p in poses:
        stack = np.stack([o[p] for o in per_trial])  # (N, J, 3)
        with np.errstate(invalid="ignore"):
            n = np.isfinite(stack[..., 0]).sum(axis=0)
            mean = np.where((n > 0)[:, None], np.nansum(stack, axis=0) / np.maximum(n, 1)[:, None], 0.0)
        offsets[p] = mean
    return OffsetModel(offsets, dict(provenance or {}))


def load_default() -> OffsetModel:
    """Returns the model fitted by bench/offset_model.py (kinect_agent.processing.offset_constants)."""
    from kinect_agent.processing import offset_constants

    offsets = {
        pose: np.array([table.get(j, (0.0, 0.0, 0.0)) for j in skeleton.JOINTS], dtype=np.float64)
        for pose, table in offset_constants.OFFSETS_M.items()
    }
    return OffsetModel(offsets, dict(offset_constants.PROVENANCE))


def correct(positions: np.ndarray) -> np.ndarray:
    """Returns positions (T, J, 3) m camera frame with the default model's offsets removed (OffsetModel.apply)."""
    return load_default().apply(positions)
