"""Forward kinematics F of the paper's 20-joint chain (Wang et al., section 4), vectorised.

Each child joint follows from its parent: T_c = T_p + R_p · R_l · (l_c · d_c), the paper's
[[R_l·R_p, T_p], [0, 1]] · [0, 0, l_c, 1]^T written with an explicit rest direction d_c, so that
identity local rotations give the neutral standing pose (arms hanging, legs straight).

Frames: the body frame of ROOT has x = the subject's left, y = up, z = forward (right-handed).
R_world_root rotates body-frame vectors into the camera frame; for a subject facing a Kinect it is
close to a half turn about y. Bone k (BONES[k] = (parent, child)) has a local rotation R_l[k]
relative to the frame of the bone entering its parent joint (for bones leaving ROOT: relative to
the ROOT frame); its world rotation is R_world[k] = R_world[entering bone] · R_l[k].
"""

from __future__ import annotations

import numpy as np

from kinect_agent import skeleton
from kinect_agent.body import _fk_numba
from kinect_agent.body.rotations import matrix_to_rotvec, quat_to_matrix

N_BONES = skeleton.J - 1

_REST = {
    "SPINE": (0.0, 1.0, 0.0), "NECK": (0.0, 1.0, 0.0), "HEAD": (0.0, 1.0, 0.0),
    "SHO_L": (1.0, -0.15, 0.0), "ELB_L": (0.0, -1.0, 0.0), "WRI_L": (0.0, -1.0, 0.0), "HAN_L": (0.0, -1.0, 0.0),
    "SHO_R": (-1.0, -0.15, 0.0), "ELB_R": (0.0, -1.0, 0.0), "WRI_R": (0.0, -1.0, 0.0), "HAN_R": (0.0, -1.0, 0.0),
    "HIP_L": (1.0, -0.35, 0.0), "KNE_L": (0.0, -1.0, 0.0), "ANK_L": (0.0, -1.0, 0.0), "FOO_L": (0.0, -0.45, 1.0),
    "HIP_R": (-1.0, -0.35, 0.0), "KNE_R": (0.0, -1.0, 0.0), "ANK_R": (0.0, -1.0, 0.0), "FOO_R": (0.0, -0.45, 1.0),
}  # fmt: skip
# REST_DIRECTIONS[k]: (3,) unit direction of bone k, child = joint k+1, in its own frame at rest.
REST_DIRECTIONS: np.ndarray = np.array([_REST[skeleton.JOINTS[c]] for _, c in skeleton.BONES])
REST_DIRECTIONS /= np.linalg.norm(REST_DIRECTIONS, axis=1, keepdims=True)

# ENTERING_BONE[k]: the bone that enters the parent joint of bone k, or -1 for bones leaving ROOT.
ENTERING_BONE: np.ndarray = np.array([p - 1 if p > 0 else -1 for p, _ in skeleton.BONES])

# Typical adult bone lengths in metres (Kinect joint placement), BONES order; used to start filters.
TYPICAL_LENGTHS: np.ndarray = np.array(
    [{"SPINE": 0.28, "NECK": 0.25, "HEAD": 0.16, "SHO_L": 0.17, "ELB_L": 0.28, "WRI_L": 0.25, "HAN_L": 0.08,
      "SHO_R": 0.17, "ELB_R": 0.28, "WRI_R": 0.25, "HAN_R": 0.08, "HIP_L": 0.09, "KNE_L": 0.42, "ANK_L": 0.40,
      "FOO_L": 0.12, "HIP_R": 0.09, "KNE_R": 0.42, "ANK_R": 0.40, "FOO_R": 0.12}[skeleton.JOINTS[c]]
     for _, c in skeleton.BONES]
)  # fmt: skip


def world_rotations(R_world_root: np.ndarray, R_local: np.ndarray) -> np.ndarray:
    """Returns the world rotation of every bone.

    R_world_root: (..., 3, 3) rotation of the ROOT body frame into the camera frame.
    R_local: (..., 19, 3, 3) local rotation of each bone relative to the bone entering its parent.
    returns: (..., 19, 3, 3) rotation of each bone's frame into the camera frame.
    """
    R_world = np.empty(np.broadcast_shapes(R_local.shape, R_world_root.shape[:-2] + (N_BONES, 3, 3)))
    for k in range(N_BONES):
        parent = R_world_root if ENTERING_BONE[k] < 0 else R_world[..., ENTERING_BONE[k], :, :]
        R_world[..., k, :, :] = parent @ R_local[..., k, :, :]
    return R_world


def forward_kinematics(
    root: np.ndarray, R_world_root: np.ndarray, lengths: np.ndarray, R_local: np.ndarray
) -> np.ndarray:
    """Returns joint positions from kinematic parameters (the observation function F).

    root: (..., 3) ROOT position, metres, camera frame.
    R_world_root: (..., 3, 3) ROOT body frame -> camera frame.
    lengths: (..., 19) bone lengths, metres, BONES order.
    R_local: (..., 19, 3, 3) local bone rotations (see module docstring).
    returns: (..., J, 3) joint positions, metres, camera frame.
    """
    R_world = world_rotations(R_world_root, R_local)
    offsets = np.einsum("...kij,kj->...ki", R_world, REST_DIRECTIONS) * lengths[..., None]
    shape = np.broadcast_shapes(root.shape[:-1], offsets.shape[:-2])
    positions = np.empty(shape + (skeleton.J, 3))
    positions[..., 0, :] = root
    for k, (p, c) in enumerate(skeleton.BONES):
        positions[..., c, :] = positions[..., p, :] + offsets[..., k, :]
    return positions


def forward_kinematics_quat(
    root: np.ndarray, q_root: np.ndarray, lengths: np.ndarray, q_local: np.ndarray
) -> np.ndarray:
    """Same as forward_kinematics with rotations as unit quaternions wxyz.

    root: (..., 3) m. q_root: (..., 4). lengths: (..., 19) m. q_local: (..., 19, 4).
    returns: (..., J, 3) m, camera frame.
    """
    return forward_kinematics(root, quat_to_matrix(q_root), lengths, quat_to_matrix(q_local))


# --- The paper's minimal parameterisation (DoF per joint), used by the filters -----------------------------------
#
# Every joint j with skeleton.DOF[j] > 0 carries one local rotation R_j shared by all bones that leave j, relative to
# the bone that enters j (ROOT: R_j is the ROOT body frame -> camera frame, and the bones leaving ROOT are rigid in
# it). Parameters theta (33 angles, radians) per joint, in joint order:
#   3 DoF: R_j = R_ref[j] · exp([v]x), v the rotation vector (3 values) relative to a per-sequence reference R_ref.
#   1 DoF (ELB_*, KNE_*): a hinge R_j = Rx(θ) about the x axis of the entering bone's frame.
#   2 DoF (WRI_*, ANK_*): R_j = Rx(a) · Rw(b), w = z for wrists, y for ankles (the axes across the bone).
# Bones that leave one joint are rigid with each other; their rest directions are personalised (ChainModel.rest).
ROT_JOINTS: tuple[int, ...] = tuple(j for j, n in enumerate(skeleton.JOINTS) if skeleton.DOF[n] > 0)  # 15 joints
ROT_INDEX: dict[int, int] = {j: r for r, j in enumerate(ROT_JOINTS)}
ROT_DOF: np.ndarray = np.array([skeleton.DOF[skeleton.JOINTS[j]] for j in ROT_JOINTS])  # (15,)
ROT_START: np.ndarray = np.concatenate(([0], np.cumsum(ROT_DOF)[:-1]))  # (15,) first theta index of each
N_THETA = int(ROT_DOF.sum())  # 33
_SECOND_AXIS = {"WRI_L": 2, "WRI_R": 2, "ANK_L": 1, "ANK_R": 1}
ROT_3DOF = np.flatnonzero(ROT_DOF == 3)  # rotation indices of 3-DoF joints (7)
ROT_1DOF = np.flatnonzero(ROT_DOF == 1)  # hinges (4)
_R2 = np.flatnonzero(ROT_DOF == 2)  # 2-DoF (4)
_R2_Y = np.array([r for r in _R2 if _SECOND_AXIS[skeleton.JOINTS[ROT_JOINTS[r]]] == 1])
_R2_Z = np.array([r for r in _R2 if _SECOND_AXIS[skeleton.JOINTS[ROT_JOINTS[r]]] == 2])
THETA_3DOF: np.ndarray = np.concatenate([ROT_START[r] + np.arange(3) for r in ROT_3DOF])  # (21,) theta indices
# BONE_GROUP[k]: rotation index (into ROT_JOINTS) of the parent joint of bone k.
BONE_GROUP: np.ndarray = np.array([ROT_INDEX[p] for p, _ in skeleton.BONES])


def _depth_levels(parents: np.ndarray) -> list[np.ndarray]:
    depth = np.zeros(len(parents), dtype=int)
    for i, p in enumerate(parents):
        depth[i] = 0 if p < 0 else depth[p] + 1
    return [np.flatnonzero(depth == d) for d in range(1, depth.max() + 1)]


_ROT_PARENT = np.array([-1 if j == 0 else ROT_INDEX[int(skeleton.PARENT[j])] for j in ROT_JOINTS])
_ROT_LEVELS = _depth_levels(_ROT_PARENT)
_JOINT_LEVELS = _depth_levels(skeleton.PARENT)


def _rx_rw(a: np.ndarray, b: np.ndarray, axis: int) -> np.ndarray:
    """Returns Rx(a) · R_axis(b), (..., 3, 3), for angle arrays a, b (...) rad."""
    ca, sa, cb, sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
    R = np.empty(np.shape(a) + (3, 3))
    if axis == 2:  # Rx(a) @ Rz(b)
        R[..., 0, 0], R[..., 0, 1], R[..., 0, 2] = cb, -sb, 0.0
        R[..., 1, 0], R[..., 1, 1], R[..., 1, 2] = ca * sb, ca * cb, -sa
        R[..., 2, 0], R[..., 2, 1], R[..., 2, 2] = sa * sb, sa * cb, ca
    else:  # Rx(a) @ Ry(b)
        R[..., 0, 0], R[..., 0, 1], R[..., 0, 2] = cb, 0.0, sb
        R[..., 1, 0], R[..., 1, 1], R[..., 1, 2] = sa * sb, ca, -sa * cb
        R[..., 2, 0], R[..., 2, 1], R[..., 2, 2] = -ca * sb, sa, ca * cb
    return R


def rodrigues(v: np.ndarray) -> np.ndarray:
    """Returns exp([v]x), (..., 3, 3), for rotation vectors v (..., 3) rad; exact series near zero."""
    th2 = np.sum(v * v, axis=-1)
    th = np.sqrt(th2)
    small = th2 < 1e-12
    safe = np.where(small, 1.0, th)
    a = np.where(small, 1.0 - th2 / 6.0, np.sin(safe) / safe)
    b = np.where(small, 0.5 - th2 / 24.0, (1.0 - np.cos(safe)) / np.where(small, 1.0, th2))
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    R = np.empty(v.shape[:-1] + (3, 3))
    R[..., 0, 0] = 1.0 - b * (y * y + z * z)
    R[..., 1, 1] = 1.0 - b * (x * x + z * z)
    R[..., 2, 2] = 1.0 - b * (x * x + y * y)
    bxy, bxz, byz = b * x * y, b * x * z, b * y * z
    R[..., 0, 1], R[..., 1, 0] = bxy - a * z, bxy + a * z
    R[..., 0, 2], R[..., 2, 0] = bxz + a * y, bxz - a * y
    R[..., 1, 2], R[..., 2, 1] = byz - a * x, byz + a * x
    return R


_REF_INDEX = np.full(len(ROT_JOINTS), -1)
_REF_INDEX[ROT_3DOF] = np.arange(len(ROT_3DOF))
_KERNEL_TABLES = (
    ROT_DOF.astype(np.int64),
    ROT_START.astype(np.int64),
    _ROT_PARENT.astype(np.int64),
    _REF_INDEX.astype(np.int64),
    np.array([_SECOND_AXIS.get(skeleton.JOINTS[j], 0) for j in ROT_JOINTS], dtype=np.int64),
    np.array([p for p, _ in skeleton.BONES], dtype=np.int64),
    BONE_GROUP.astype(np.int64),
)


class ChainModel:
    """The kinematic chain F(root, lengths, theta) with personalised rest directions and 3-DoF references.

    rest: (19, 3) unit rest direction of each bone in the frame of its parent joint's rotation (BONES order).
    R_ref: (7, 3, 3) reference rotation of each 3-DoF joint (ROOT, SPINE, NECK, SHO_L, SHO_R, HIP_L, HIP_R).
    """

    def __init__(self, rest: np.ndarray | None = None, R_ref: np.ndarray | None = None, compiled: bool = True) -> None:
        self.compiled = compiled  # use the numba kernel when numba is installed
        self.rest = np.array(REST_DIRECTIONS if rest is None else rest, dtype=np.float64)
        self.R_ref = np.tile(np.eye(3), (len(ROT_3DOF), 1, 1)) if R_ref is None else np.array(R_ref, dtype=np.float64)
        if self.rest.shape != (N_BONES, 3):
            raise ValueError(f"rest must have shape (19, 3), got {self.rest.shape}")
        if self.R_ref.shape != (len(ROT_3DOF), 3, 3):
            raise ValueError(f"R_ref must have shape ({len(ROT_3DOF)}, 3, 3), got {self.R_ref.shape}")

    def local_rotations(self, theta: np.ndarray) -> np.ndarray:
        """Returns R_j for the 15 rotating joints, (..., 15, 3, 3), from theta (..., 33) rad."""
        lead = theta.shape[:-1]
        R = np.empty(lead + (len(ROT_JOINTS), 3, 3))
        v = theta[..., THETA_3DOF].reshape(lead + (len(ROT_3DOF), 3))
        R[..., ROT_3DOF, :, :] = self.R_ref @ rodrigues(v)
        h = theta[..., ROT_START[ROT_1DOF]]
        c, s = np.cos(h), np.sin(h)
        Rh = np.zeros(h.shape + (3, 3))
        Rh[..., 0, 0] = 1.0
        Rh[..., 1, 1], Rh[..., 1, 2], Rh[..., 2, 1], Rh[..., 2, 2] = c, -s, s, c
        R[..., ROT_1DOF, :, :] = Rh
        for group, axis in ((_R2_Z, 2), (_R2_Y, 1)):
            R[..., group, :, :] = _rx_rw(theta[..., ROT_START[group]], theta[..., ROT_START[group] + 1], axis)
        return R

    def global_rotations(self, R_local: np.ndarray) -> np.ndarray:
        """Returns G_j = world rotation of the bones leaving each rotating joint, (..., 15, 3, 3)."""
        G = R_local.copy()
        for level in _ROT_LEVELS:
            G[..., level, :, :] = G[..., _ROT_PARENT[level], :, :] @ R_local[..., level, :, :]
        return G

    def positions(self, root: np.ndarray, lengths: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Returns joint positions (..., J, 3), metres, camera frame.

        root: (..., 3) m. lengths: (..., 19) m, BONES order. theta: (..., 33) rad (see ROT_JOINTS).
        """
        if _fk_numba.AVAILABLE and self.compiled:
            return self.positions_compiled(root, lengths, theta)
        return self.positions_numpy(root, lengths, theta)

    def positions_compiled(self, root: np.ndarray, lengths: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Same as positions_numpy, by the compiled kernel of _fk_numba (one loop per state)."""
        lead = np.broadcast_shapes(root.shape[:-1], lengths.shape[:-1], theta.shape[:-1])
        r = np.ascontiguousarray(np.broadcast_to(root, lead + (3,)), dtype=np.float64).reshape(-1, 3)
        ln = np.ascontiguousarray(np.broadcast_to(lengths, lead + (N_BONES,)), dtype=np.float64).reshape(-1, N_BONES)
        th = np.ascontiguousarray(np.broadcast_to(theta, lead + (N_THETA,)), dtype=np.float64).reshape(-1, N_THETA)
        out = np.empty((r.shape[0], skeleton.J, 3))
        _fk_numba.fk_many(r, ln, th, self.rest, self.R_ref, *_KERNEL_TABLES, out)
        return out.reshape(lead + (skeleton.J, 3))

    @property
    def runs_compiled(self) -> bool:
        """True when positions (and positions_into) run the compiled kernel: numba installed and self.compiled."""
        return _fk_numba.AVAILABLE and self.compiled

    def positions_into(self, root: np.ndarray, lengths: np.ndarray, theta: np.ndarray, out: np.ndarray) -> None:
        """Writes the joint positions of S states into out (S, J, 3) m by the compiled kernel (needs runs_compiled).

        root: (S, 3) m. lengths: (S, 19) m. theta: (S, 33) rad; views need not be contiguous. No copies are made.
        """
        _fk_numba.fk_many(root, lengths, theta, self.rest, self.R_ref, *_KERNEL_TABLES, out)

    def fold_references(self, theta: np.ndarray, limit_rad: float = 1.5) -> None:
        """Folds 3-DoF rotation vectors longer than limit_rad into the references, so they stay far from ±π.

        theta: (33,) rad, changed in place (those rotation vectors become zero); self.R_ref changes to match, so
        positions(root, lengths, theta) is the same rotation as before.
        """
        v = theta[THETA_3DOF].reshape(len(ROT_3DOF), 3)
        big = np.linalg.norm(v, axis=1) > limit_rad
        if big.any():
            self.R_ref[big] = self.R_ref[big] @ rodrigues(v[big])
            v[big] = 0.0
            theta[THETA_3DOF] = v.reshape(-1)

    def rebase(self, theta: np.ndarray, refs: np.ndarray) -> np.ndarray:
        """Returns theta (T, 33) rad with its 3-DoF rotation vectors, given against refs (T, 7, 3, 3), re-expressed
        against self.R_ref (the other angles unchanged)."""
        T = len(theta)
        v = theta[:, THETA_3DOF].reshape(T, len(ROT_3DOF), 3)
        R = refs @ rodrigues(v)
        out = theta.copy()
        out[:, THETA_3DOF] = matrix_to_rotvec(np.swapaxes(self.R_ref, -1, -2) @ R).reshape(T, -1)
        return out

    def positions_numpy(self, root: np.ndarray, lengths: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Returns joint positions (..., J, 3) m by numpy broadcasting (reference implementation)."""
        G = self.global_rotations(self.local_rotations(theta))
        offsets = np.einsum("...kij,kj->...ki", G[..., BONE_GROUP, :, :], self.rest) * lengths[..., None]
        shape = np.broadcast_shapes(root.shape[:-1], offsets.shape[:-2])
        pos = np.empty(shape + (skeleton.J, 3))
        pos[..., 0, :] = root
        for level in _JOINT_LEVELS:
            pos[..., level, :] = pos[..., skeleton.PARENT[level], :] + offsets[..., level - 1, :]
        return pos

    def standard_rotations(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Returns (R_world_root (..., 3, 3), R_local (..., 19, 3, 3)) for `forward_kinematics` with REST_DIRECTIONS.

        Each bone's frame is turned so that REST_DIRECTIONS[k] maps onto this model's rest[k]; with the same root
        and lengths, forward_kinematics then gives exactly `positions`.
        """
        from kinect_agent.body.rotations import rotation_between

        G = self.global_rotations(self.local_rotations(theta))
        C = rotation_between(REST_DIRECTIONS, self.rest)  # (19, 3, 3)
        W = G[..., BONE_GROUP, :, :] @ C  # world rotation of each bone's standard frame
        R_world_root = G[..., 0, :, :]
        W_in = np.empty_like(W)
        for k in range(N_BONES):
            W_in[..., k, :, :] = R_world_root if ENTERING_BONE[k] < 0 else W[..., ENTERING_BONE[k], :, :]
        R_local = np.swapaxes(W_in, -1, -2) @ W
        return R_world_root, R_local


def _step_tables() -> np.ndarray:
    """Returns the int64 (9, 33) table of the fused UKF kernel (_ukf_numba: rows named there), -1 padded."""
    theta_rot = np.repeat(np.arange(len(ROT_JOINTS)), ROT_DOF)
    last_rot = np.full(skeleton.J, -1)
    for k, (p, c) in enumerate(skeleton.BONES):  # parents come before children
        last_rot[c] = max(int(BONE_GROUP[k]), int(last_rot[p]))
    rows = [*_KERNEL_TABLES, theta_rot, last_rot]
    out = np.full((len(rows), N_THETA), -1, dtype=np.int64)
    for i, row in enumerate(rows):
        out[i, : len(row)] = row
    return out


STEP_TABLES: np.ndarray = _step_tables()
