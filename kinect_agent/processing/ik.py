"""Inverse kinematics: joint positions -> initial kinematic parameters of the ChainModel (frame by frame, closed form).

Used to start the UKF (kinect_agent.processing.ukf) and to personalise the chain. Each joint's frame follows from
measured directions, vectorised over frames:
    ROOT   y = SPINE − ROOT, x ≈ HIP_L − HIP_R (orthogonalised);  NECK bone: y = NECK − SPINE, x ≈ SHO_L − SHO_R
    NECK   y = HEAD − NECK, x ≈ SHO_L − SHO_R
    SHO/HIP  y = −(ELB − SHO) (bone points along −y), x = elbow/knee hinge axis ∝ forearm × upper arm (thigh × shank
             for legs), blended with the parent's x so that a straight limb keeps a defined axis
    ELB/KNE  hinge angle about x; WRI/ANK two angles Rx(a)·Rw(b) that turn the rest direction onto the measured one.
Rest directions of the rigid bone groups (ROOT: SPINE/HIP_L/HIP_R; NECK: HEAD/SHO_L/SHO_R) are averaged over frames
(personalised); the 3-DoF references R_ref are the chordal means of each joint's rotations, so the filter's rotation
vectors stay well inside ±π for ordinary exercises.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from kinect_agent import skeleton
from kinect_agent.body import kinematics as km
from kinect_agent.body.rotations import (
    axis_rotation,
    frame_from_axes,
    matrix_to_quat,
    matrix_to_rotvec,
    quat_mean,
    quat_to_matrix,
)

IDX = skeleton.INDEX
# A subject facing the camera: body frame (x left, y up, z forward) -> camera frame (z away from the camera).
R_FACING: np.ndarray = axis_rotation(1, np.pi)


@dataclass
class IKResult:
    """Initial parameters. model: the personalised chain. root: (T, 3) m. lengths: (19,) m. theta: (T, 33) rad."""

    model: km.ChainModel
    root: np.ndarray
    lengths: np.ndarray
    theta: np.ndarray


def fill_gaps(positions: np.ndarray) -> np.ndarray:
    """Returns positions (T, J, 3) m with NaN gaps filled: linear in time per joint, nearest at the ends.

    A joint never observed is placed at its parent plus its typical bone length along the rest direction of a
    subject facing the camera. Raises ValueError when no joint is observed in any frame.
    """
    pos = np.array(positions, dtype=np.float64)
    T = pos.shape[0]
    ok = np.all(np.isfinite(pos), axis=-1)  # (T, J)
    if not ok.any():
        raise ValueError("no joint is observed in any frame: nothing to filter")
    frames = np.arange(T)
    for j in range(skeleton.J):
        good = ok[:, j]
        if good.all():
            continue
        if good.any():
            for a in range(3):
                pos[:, j, a] = np.interp(frames, frames[good], pos[good, j, a])
        elif j == 0:  # ROOT never seen: the centroid of what is seen, interpolated over frames without any
            others = np.where(ok[..., None], pos, 0.0).sum(axis=1)
            count = ok.sum(axis=1)[:, None]
            pos[:, 0] = _fill_rows(np.where(count > 0, others / np.maximum(count, 1), np.nan))
        else:
            p = skeleton.PARENT[j]
            pos[:, j] = pos[:, p] + R_FACING @ km.REST_DIRECTIONS[j - 1] * km.TYPICAL_LENGTHS[j - 1]
    return pos


def _fill_rows(x: np.ndarray) -> np.ndarray:
    """Fills NaN rows of x (T, 3) by linear interpolation over the finite rows."""
    good = np.all(np.isfinite(x), axis=-1)
    if good.all() or not good.any():
        return np.nan_to_num(x)
    f = np.arange(len(x))
    return np.stack([np.interp(f, f[good], x[good, a]) for a in range(3)], axis=-1)


def _fill_frames(R: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """Replaces non-finite rotations in R (T, 3, 3) by the nearest finite frame's (or `fallback` (3, 3))."""
    good = np.all(np.isfinite(R), axis=(-1, -2))
    if good.all():
        return R
    if not good.any():
        return np.broadcast_to(fallback, R.shape).copy()
    idx = np.arange(len(R))
    nearest = np.interp(idx, idx[good], idx[good]).round().astype(int)
    src = np.where(good, idx, nearest)
    return R[src]


def bone_length_estimate(positions: np.ndarray) -> np.ndarray:
    """Returns (19,) m: median length of each bone over the frames where both ends are observed (typical if none)."""
    lengths = skeleton.bone_lengths(positions)
    seen = np.isfinite(lengths).any(axis=0)
    est = np.full(lengths.shape[-1], np.nan)
    if seen.any():
        est[seen] = np.nanmedian(lengths[:, seen], axis=0)
    est = np.where(np.isfinite(est) & (est > 1e-3), est, km.TYPICAL_LENGTHS)
    return est


def _unit(v: np.ndarray) -> np.ndarray:
    with np.errstate(invalid="ignore", divide="ignore"):
        return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _mean_direction(R: np.ndarray, vec: np.ndarray, default: np.ndarray) -> np.ndarray:
    """Returns the unit mean over frames of R^T vec (direction in the local frame). R: (T, 3, 3). vec: (T, 3)."""
    local = _unit(np.einsum("tji,tj->ti", R, vec))
    mean = np.nanmean(np.where(np.isfinite(local), local, np.nan), axis=0) if len(local) else default
    n = np.linalg.norm(mean)
    return mean / n if np.isfinite(n) and n > 1e-6 else default


def _limb(parent: np.ndarray, prox: np.ndarray, mid: np.ndarray, dist: np.ndarray, sign: float) -> tuple:
    """Returns (U, theta_hinge): the proximal segment's world frame and the hinge angle at `mid`.

    parent: (T, 3, 3) world frame of the parent joint. prox, mid, dist: (T, 3) m positions (e.g. SHO, ELB, WRI).
    sign: +1 for arms (elbow bends forward), −1 for legs (knee bends backward), so the hinge axis points left.
    """
    u = _unit(mid - prox)
    f = _unit(dist - mid)
    c = sign * np.cross(f, u)  # exact hinge axis times sin(bend)
    # Near a straight limb the axis is undefined: lean on the parent's x axis there (only below ~6° of bend).
    lean = 0.1 * np.clip(1.0 - np.linalg.norm(c, axis=-1, keepdims=True) / 0.1, 0.0, 1.0)
    hint = c + lean * parent[..., :, 0]
    U = frame_from_axes(-u, hint)
    U = _fill_frames(U, parent[0] if np.all(np.isfinite(parent[0])) else np.eye(3))
    d = np.einsum("tji,tj->ti", U, f)
    theta = np.arctan2(-d[:, 2], -d[:, 1])
    return U, np.nan_to_num(theta)


def _two_dof(F: np.ndarray, vec: np.ndarray, rest: np.ndarray, axis: int) -> tuple[np.ndarray, np.ndarray]:
    """Returns angles (a, b), each (T,) rad, with Rx(a)·R_axis(b)·rest ≈ unit(F^T vec). F: (T, 3, 3). vec: (T, 3)."""
    h = _unit(np.einsum("tji,tj->ti", F, vec))
    w = np.eye(3)[axis]
    gain = np.cross(w, rest)[0]
    b = np.arcsin(np.clip(h[:, 0] / gain, -1.0, 1.0))
    v = axis_rotation(axis, b) @ rest
    a = np.arctan2(h[:, 2], h[:, 1]) - np.arctan2(v[:, 2], v[:, 1])
    a = (a + np.pi) % (2 * np.pi) - np.pi
    return np.nan_to_num(a), np.nan_to_num(b)


def inverse_kinematics(positions: np.ndarray) -> IKResult:
    """Returns the personalised chain and per-frame parameters that reproduce `positions` approximately.

    positions: (T, J, 3) float, metres, camera frame, NaN = untracked (gaps are filled by `fill_gaps`).
    """
    positions = np.asarray(positions, dtype=np.float64)
    if positions.ndim != 3 or positions.shape[1:] != (skeleton.J, 3) or positions.shape[0] < 1:
        raise ValueError(f"positions must have shape (T>=1, {skeleton.J}, 3), got {positions.shape}")
    lengths = bone_length_estimate(positions)
    p = fill_gaps(positions)
    T = p.shape[0]
    J = lambda name: p[:, IDX[name]]  # noqa: E731
    rest = km.REST_DIRECTIONS.copy()
    R = {}  # world frame of the bones leaving each rotating joint, (T, 3, 3)
    loc = {}  # local rotation of each 3-DoF joint
    R0 = frame_from_axes(J("SPINE") - J("ROOT"), J("HIP_L") - J("HIP_R"))
    R["ROOT"] = _fill_frames(R0, R_FACING)
    loc["ROOT"] = R["ROOT"]
    for name in ("SPINE", "HIP_L", "HIP_R"):
        k = IDX[name] - 1
        rest[k] = _mean_direction(R["ROOT"], J(name) - J("ROOT"), rest[k])
    across = J("SHO_L") - J("SHO_R")
    R["SPINE"] = _fill_frames(frame_from_axes(J("NECK") - J("SPINE"), across), R["ROOT"][0])
    loc["SPINE"] = np.swapaxes(R["ROOT"], -1, -2) @ R["SPINE"]
    R["NECK"] = _fill_frames(frame_from_axes(J("HEAD") - J("NECK"), across), R["SPINE"][0])
    loc["NECK"] = np.swapaxes(R["SPINE"], -1, -2) @ R["NECK"]
    for name in ("HEAD", "SHO_L", "SHO_R"):
        k = IDX[name] - 1
        rest[k] = _mean_direction(R["NECK"], J(name) - J("NECK"), rest[k])
    angles = {}
    for side in "LR":
        for top, mid, low, end, par, sign, axis in (
            ("SHO", "ELB", "WRI", "HAN", "NECK", 1.0, 2),
            ("HIP", "KNE", "ANK", "FOO", "ROOT", -1.0, 1),
        ):
            t_, m_, l_, e_ = (f"{x}_{side}" for x in (top, mid, low, end))
            U, hinge = _limb(R[par], J(t_), J(m_), J(l_), sign)
            R[t_] = U
            loc[t_] = np.swapaxes(R[par], -1, -2) @ U
            angles[m_] = hinge[:, None]
            F = U @ axis_rotation(0, hinge)
            a, b = _two_dof(F, J(e_) - J(l_), rest[IDX[e_] - 1], axis)
            angles[l_] = np.stack((a, b), axis=-1)
    R_ref = np.empty((len(km.ROT_3DOF), 3, 3))
    theta = np.zeros((T, km.N_THETA))
    for r, j in enumerate(km.ROT_JOINTS):
        name = skeleton.JOINTS[j]
        s = km.ROT_START[r]
        if km.ROT_DOF[r] == 3:
            i3 = int(np.flatnonzero(km.ROT_3DOF == r)[0])
            ref = quat_to_matrix(quat_mean(matrix_to_quat(loc[name])))
            R_ref[i3] = ref
            theta[:, s : s + 3] = matrix_to_rotvec(ref.T @ loc[name])
        else:
            theta[:, s : s + km.ROT_DOF[r]] = angles[name]
    theta = np.nan_to_num(theta)
    return IKResult(km.ChainModel(rest, R_ref), p[:, 0].copy(), lengths, theta)
