"""Left/right label swaps of a monocular landmarker: frames whose L/R labelling fits the frame before it better
mirrored.

Seen from the side, a monocular pose model cannot tell which way the person faces and now and then gives the near
limbs the far limbs' labels (BlazePose on Pose2Sim's side view cam02: 29 such flips in 100 frames, the whole body
swapped in about half of the frames; bench/README.md, "Webcam angles: why the pipeline made them worse"). The
landmarker's labelling is then not a continuous signal, and a temporal filter that runs across a flip averages the
left limb with the right one: the knee and elbow angles of such an average belong to neither. The joint smoother
(joint_smoother.py) therefore restarts at every flip.

A frame k is a flip when, with the root subtracted (positions relative to ROOT, so that a jump of the whole body's
fitted distance does not count),

    sum_j |p_k[mirror(j)] - p_{k-1}[j]|^2  <  sum_j |p_k[j] - p_{k-1}[j]|^2       (over joints present in both)

No margin: a frame where both labellings fit about as well (the legs crossing in a side view) may count as a flip,
which only costs the smoother a restart, never a wrong label.

The landmarker also swaps the arms alone, the legs keeping their labels (cam02 of the same demo: frames 79-84 swap
the shoulders back and forth while the legs, which dominate the sum above, do not). A filter run across such swaps
averages the left shoulder with the right one, the shoulder line it smooths shrinks to a few centimetres, and the
trunk's left and forward axes (kinect_agent.body.angles.body_frame) turn by tens of degrees: shoulder flexion 38
degrees off in one frame. pair_swaps finds them, one mirrored pair at a time:

    |p_k[R] - p_{k-1}[L]|^2 + |p_k[L] - p_{k-1}[R]|^2  <  |p_k[L] - p_{k-1}[L]|^2 + |p_k[R] - p_{k-1}[R]|^2
"""

from __future__ import annotations

import numpy as np

from kinect_agent import skeleton


def _mirror_index() -> np.ndarray:
    """Returns (J,) int: the index of each joint's mirror image (X_L <-> X_R; the trunk's joints map to themselves)."""
    out = np.arange(skeleton.J)
    for j, name in enumerate(skeleton.JOINTS):
        if name.endswith(("_L", "_R")):
            out[j] = skeleton.INDEX[name[:-1] + ("R" if name.endswith("_L") else "L")]
    return out


MIRROR: np.ndarray = _mirror_index()


def labelling_flips(positions: np.ndarray) -> np.ndarray:
    """Returns (T,) bool: True at frames whose L/R labelling fits the previous frame better mirrored (module
    docstring); frame 0 and frames without ROOT in either frame are never flips.

    positions: (T, J, 3) float, metres, any frame; NaN = untracked.
    """
    if positions.ndim != 3 or positions.shape[1:] != (skeleton.J, 3):
        raise ValueError(f"positions must have shape (T, {skeleton.J}, 3), got {positions.shape}")
    rel = positions - positions[:, :1]
    now, before = rel[1:], rel[:-1]
    same = (now - before) ** 2
    mirrored = (now[:, MIRROR] - before) ** 2
    both = np.isfinite(same) & np.isfinite(mirrored)
    flip = np.where(both, mirrored, 0.0).sum(axis=(1, 2)) < np.where(both, same, 0.0).sum(axis=(1, 2))
    return np.concatenate(([False], flip & both.any(axis=(1, 2))))


ARM_PAIRS: tuple[tuple[int, int], ...] = tuple(
    (skeleton.INDEX[f"{name}_L"], skeleton.INDEX[f"{name}_R"]) for name in ("SHO", "ELB", "WRI", "HAN")
)  # the arms' mirrored pairs, (left, right) joint indices


def pair_swaps(positions: np.ndarray, pairs: tuple[tuple[int, int], ...] = ARM_PAIRS) -> np.ndarray:
    """Returns (T,) bool: True at frames where at least one mirrored pair of joints (pairs: (left, right) indices)
    fits the previous frame better swapped (module docstring), with the root subtracted; frame 0, and a pair missing
    a joint in either frame, never.

    positions: (T, J, 3) float, metres, any frame; NaN = untracked.
    """
    if positions.ndim != 3 or positions.shape[1:] != (skeleton.J, 3):
        raise ValueError(f"positions must have shape (T, {skeleton.J}, 3), got {positions.shape}")
    rel = positions - positions[:, :1]
    now, before = rel[1:], rel[:-1]
    out = np.zeros(len(positions), dtype=bool)
    for left, right in pairs:
        same = ((now[:, left] - before[:, left]) ** 2).sum(-1) + ((now[:, right] - before[:, right]) ** 2).sum(-1)
        swapped = ((now[:, right] - before[:, left]) ** 2).sum(-1) + ((now[:, left] - before[:, right]) ** 2).sum(-1)
        with np.errstate(invalid="ignore"):  # NaN compares False: a pair missing a joint is no swap
            out[1:] |= swapped < same
    return out


def body_jumps(positions: np.ndarray, t: np.ndarray, speed_m_s: float, noise_m: float) -> np.ndarray:
    """Returns (T,) bool: True at frames where ROOT moved across the image (x, y) farther from the previous frame than
    a body moves (speed_m_s times the interval, plus noise_m): another person taken for the patient, or the
    patient found again elsewhere; frame 0 and frames without ROOT in either frame are never jumps.

    positions: (T, J, 3) float, metres, camera frame (z the depth); t: (T,) s.
    """
    root = positions[:, 0, :2]
    step = np.linalg.norm(np.diff(root, axis=0), axis=1)
    limit = speed_m_s * np.diff(t) + noise_m
    with np.errstate(invalid="ignore"):
        return np.concatenate(([False], step > limit))


__all__ = ["ARM_PAIRS", "MIRROR", "body_jumps", "labelling_flips", "pair_swaps"]
