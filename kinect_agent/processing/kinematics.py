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
from kinect_agent.processing.rotations import quat_to_matrix

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
