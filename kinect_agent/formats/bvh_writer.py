"""BVH writer: a filtered recording as the kinematic model's motion (segment lengths as OFFSETs, rotations per joint).

Hierarchy: the 20-joint tree (skeleton.PARENT) with CMU joint names (mocap_mapping.CMU_TO_OURS, so that
formats.bvh.read maps them back); HAN_* and FOO_* are the End Sites of the wrists and ankles, HEAD a joint with a
zero End Site. Hips carries 6 channels (position, cm, camera frame: x side, y up, z away from the camera), every
other joint 3 (`Zrotation Xrotation Yrotation`, degrees: R_parent_joint = Rz @ Rx @ Ry, as formats.bvh composes).
OFFSETs are in cm, in the parent joint's frame at rest: the rigid groups (ROOT: SPINE/HIP_L/HIP_R; NECK:
HEAD/SHO_L/SHO_R) keep their mean shape in the body frame (x left, y up, z forward, like processing.ik); every other
bone has its median length along kinematics.REST_DIRECTIONS (arms and legs hanging down).
Rotations are recovered from the positions: the rigid groups by a least-squares (Kabsch) fit of their mean shape;
a joint with one child by the smallest rotation, relative to its parent's frame, that points the bone from the
rebuilt parent position at the recorded child (so errors do not add up along a limb). Rotation about a limb's own
axis is not seen in joint centres and is left at its smallest value. Frames are written at the median frame
interval (BVH has one Frame Time); gaps (NaN) are filled linearly in time before fitting.
"""

from __future__ import annotations

import io

import numpy as np

from kinect_agent import skeleton
from kinect_agent.body.kinematics import REST_DIRECTIONS
from kinect_agent.body.rotations import frame_from_axes, rotation_between

CM_PER_M = 100.0
BVH_NAMES: dict[str, str] = {
    "ROOT": "Hips", "SPINE": "Spine", "NECK": "Neck", "HEAD": "Head",
    "SHO_L": "LeftArm", "ELB_L": "LeftForeArm", "WRI_L": "LeftHand",
    "SHO_R": "RightArm", "ELB_R": "RightForeArm", "WRI_R": "RightHand",
    "HIP_L": "LeftUpLeg", "KNE_L": "LeftLeg", "ANK_L": "LeftFoot",
    "HIP_R": "RightUpLeg", "KNE_R": "RightLeg", "ANK_R": "RightFoot",
}  # fmt: skip
END_SITES = ("HAN_L", "HAN_R", "FOO_L", "FOO_R")  # written as End Sites of the wrists and ankles
ROTATION_ORDER = "ZXY"
_GROUPS = {"ROOT": ("SPINE", "HIP_L", "HIP_R"), "NECK": ("HEAD", "SHO_L", "SHO_R")}  # (y towards, x from 3rd to 2nd)
_IDX = skeleton.INDEX


def _children(j: int) -> list[int]:
    return [c for c in range(skeleton.J) if skeleton.PARENT[c] == j]


ROTATING = tuple(skeleton.JOINTS[j] for j in range(skeleton.J) if _children(j))  # joints with a BVH rotation


def fill_gaps(t: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """Returns positions (T, J, 3) m with NaN samples filled linearly in time (ends held); ValueError for a joint
    never tracked. t: (T,) s."""
    out = np.array(positions, dtype=np.float64)
    for j in range(skeleton.J):
        ok = np.isfinite(out[:, j]).all(axis=-1)
        if not ok.any():
            raise ValueError(f"joint {skeleton.JOINTS[j]} is never tracked; BVH needs every joint")
        if not ok.all():
            for axis in range(3):
                out[:, j, axis] = np.interp(t, t[ok], out[ok, j, axis])
    return out


def group_shape(positions: np.ndarray, joint: str) -> dict[str, np.ndarray]:
    """Returns {child: (3,) m}, the mean offsets of a rigid group's children in the body frame (x left, y up).

    positions: (T, J, 3) m, camera frame, finite.
    """
    up_child, left, right = _GROUPS[joint]
    p = positions[:, _IDX[joint]]
    F = frame_from_axes(positions[:, _IDX[up_child]] - p, positions[:, _IDX[left]] - positions[:, _IDX[right]])
    return {c: np.nanmean(np.einsum("tji,tj->ti", F, positions[:, _IDX[c]] - p), axis=0) for c in _GROUPS[joint]}


def kabsch(local: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Returns rotations (T, 3, 3) best turning local vectors (K, 3) onto target vectors (T, K, 3), least squares."""
    H = np.einsum("ki,tkj->tij", local, target)  # (T, 3, 3) = sum_k local_k target_k^T
    U, _, Vt = np.linalg.svd(H)
    V = np.swapaxes(Vt, -1, -2)
    d = np.sign(np.linalg.det(V @ np.swapaxes(U, -1, -2)))
    D = np.zeros_like(H)
    D[:, 0, 0] = D[:, 1, 1] = 1.0
    D[:, 2, 2] = d
    return V @ D @ np.swapaxes(U, -1, -2)


def offsets(positions: np.ndarray) -> np.ndarray:
    """Returns the rest offsets (J, 3) m of every joint in its parent's frame (ROOT: zeros).

    positions: (T, J, 3) m, camera frame, finite.
    """
    out = np.zeros((skeleton.J, 3))
    lengths = np.median(skeleton.bone_lengths(positions), axis=0)  # (J-1,) m
    for k, (_, c) in enumerate(skeleton.BONES):
        out[c] = REST_DIRECTIONS[k] * lengths[k]
    for joint in _GROUPS:
        for child, v in group_shape(positions, joint).items():
            out[_IDX[child]] = v
    return out


def fit_rotations(positions: np.ndarray, rest: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Returns (R_parent_joint (T, J, 3, 3), rebuilt positions (T, J, 3) m) of the model with offsets `rest`.

    positions: (T, J, 3) m, camera frame, finite. rest: (J, 3) m, offsets() output. Leaves get the identity.
    """
    T = positions.shape[0]
    R_world = np.broadcast_to(np.eye(3), (T, skeleton.J, 3, 3)).copy()
    R_local = R_world.copy()
    rebuilt = np.empty_like(positions)
    rebuilt[:, 0] = positions[:, 0]
    for j in range(skeleton.J):
        kids = _children(j)
        parent = int(skeleton.PARENT[j])
        R_parent = R_world[:, parent] if parent >= 0 else np.broadcast_to(np.eye(3), (T, 3, 3))
        if not kids:
            R_world[:, j] = R_parent
        elif len(kids) > 1:
            R_world[:, j] = kabsch(rest[kids], positions[:, kids] - rebuilt[:, j, None])
        else:
            c = kids[0]
            rest_world = np.einsum("tij,j->ti", R_parent, rest[c])
            swing = rotation_between(rest_world, positions[:, c] - rebuilt[:, j])
            R_world[:, j] = swing @ R_parent
        R_local[:, j] = np.swapaxes(R_parent, -1, -2) @ R_world[:, j]
        for c in kids:
            rebuilt[:, c] = rebuilt[:, j] + np.einsum("tij,j->ti", R_world[:, j], rest[c])
    return R_local, rebuilt


def euler_zxy(R: np.ndarray) -> np.ndarray:
    """Returns angles (..., 3) degrees (z, x, y) with R = Rz(z) @ Rx(x) @ Ry(y); at x = ±90° y is 0.

    R: (..., 3, 3) rotation matrices.
    """
    x = np.arcsin(np.clip(R[..., 2, 1], -1.0, 1.0))
    cx = np.cos(x)
    gimbal = cx < 1e-9
    z = np.where(gimbal, np.arctan2(R[..., 1, 0], R[..., 0, 0]), np.arctan2(-R[..., 0, 1], R[..., 1, 1]))
    y = np.where(gimbal, 0.0, np.arctan2(-R[..., 2, 0], R[..., 2, 2]))
    return np.degrees(np.stack((z, x, y), axis=-1))


def frame_time(t: np.ndarray) -> float:
    """Returns the BVH Frame Time: the median frame interval of t (T,) s, or 1/30 s for one frame."""
    return float(np.median(np.diff(t))) if t.shape[0] > 1 else 1.0 / 30.0


def _hierarchy(rest_cm: np.ndarray) -> list[str]:
    lines = ["HIERARCHY"]

    def block(j: int, depth: int) -> None:
        pad = "  " * depth
        name = skeleton.JOINTS[j]
        lines.append(f"{pad}{'ROOT' if j == 0 else 'JOINT'} {BVH_NAMES[name]}")
        lines.append(f"{pad}{{")
        lines.append(f"{pad}  OFFSET {_fmt(rest_cm[j], 4)}")
        rot = " ".join(f"{a}rotation" for a in ROTATION_ORDER)
        channels = f"6 Xposition Yposition Zposition {rot}" if j == 0 else f"3 {rot}"
        lines.append(f"{pad}  CHANNELS {channels}")
        kids = _children(j)
        for c in kids:
            if skeleton.JOINTS[c] in END_SITES:
                lines.extend([f"{pad}  End Site", f"{pad}  {{", f"{pad}    OFFSET {_fmt(rest_cm[c], 4)}", f"{pad}  }}"])
            else:
                block(c, depth + 1)
        if not kids:
            lines.extend([f"{pad}  End Site", f"{pad}  {{", f"{pad}    OFFSET 0.0000 0.0000 0.0000", f"{pad}  }}"])
        lines.append(f"{pad}}}")

    block(0, 0)
    return lines


def _fmt(values: np.ndarray, digits: int) -> str:
    return " ".join(f"{v:.{digits}f}" for v in values)


def bvh_joint_order() -> list[int]:
    """Returns our joint indices in the order their BVH channels appear (depth first, End Sites left out)."""
    order: list[int] = []

    def visit(j: int) -> None:
        order.append(j)
        for c in _children(j):
            if skeleton.JOINTS[c] in END_SITES:
                continue
            visit(c)

    visit(0)
    return order


def write_text(t: np.ndarray, positions: np.ndarray) -> str:
    """Returns the BVH text of a filtered recording.

    t: (T,) s, increasing. positions: (T, J, 3) m, camera frame, NaN = untracked (filled in time).
    """
    t = np.asarray(t, dtype=np.float64)
    positions = np.asarray(positions, dtype=np.float64)
    if positions.ndim != 3 or positions.shape[1:] != (skeleton.J, 3) or positions.shape[0] != t.shape[0]:
        raise ValueError(f"positions must have shape ({t.shape[0]}, {skeleton.J}, 3), got {positions.shape}")
    filled = fill_gaps(t, positions)
    rest = offsets(filled)
    R_local, _ = fit_rotations(filled, rest)
    order = bvh_joint_order()
    angles = euler_zxy(R_local[:, order])  # (T, N, 3) degrees
    motion = np.concatenate([filled[:, 0] * CM_PER_M, angles.reshape(t.shape[0], -1)], axis=1)
    out = io.StringIO()
    out.write("\n".join(_hierarchy(rest * CM_PER_M)) + "\n")
    out.write(f"MOTION\nFrames: {t.shape[0]}\nFrame Time: {frame_time(t):.6f}\n")
    for row in motion:
        out.write(_fmt(row, 6) + "\n")
    return out.getvalue()
