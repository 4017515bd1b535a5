"""Re-estimates the chain's bone vectors (segment lengths and rest directions) given the smoothed rotations.

The smoother fits root(t) and the angles θ(t) with the bone vectors fixed after passes 1-2. Joint positions are
linear in the bone vectors once the rotations are known (kinematics.ChainModel):
    p_j(t) = root(t) + G_0(t) v_0 + Σ_{k on the path ROOT → j} G_g(k)(t) v_k,
with v_k = l_k · rest_k (3,) m the bone vector in the frame of its parent joint's rotation group g(k), G_g(t) that
frame's rotation into the camera frame, and v_0 an extra constant offset of ROOT in the ROOT frame (0 before). Given
the smoothed G(t) and root(t), the v that minimise the weighted squared residual Σ_t,j w_j(t) |z_j(t) − p_j(t)|²
over the observed joint-frames are one linear least-squares solve (60 unknowns), the next step of a block
coordinate descent of the same fit. It lets each bone take the length and direction the measurements have on
average over the whole recording (passes 1-2's lengths from the UKF's random walk leave a mean misfit that moves the
joints' means), and the chain stays rigid: lengths are constants, rest directions constants in their frames.
A study tool of bench/k1_bias.py, not used by the pipeline: it brings the bias to the clean measurement's, which
helps some simulated motions and loses on others and on the real KERAAL pairs (bench/README.md, "Kinect 1: where
the offline bias ... comes from", item 5).

Normal equations, 3 × 3 blocks for bones k, m (the ROOT offset counts as a bone above all others):
    A_km = Σ_t S_d(t) G_k(t)ᵀ G_m(t),  d the deeper of k, m when one is on the other's path (else 0),
    b_k  = Σ_t G_k(t)ᵀ Y_k(t),
with S_d(t) = Σ_{j below d} w_j(t) and Y_k(t) = Σ_{j below k} w_j(t) (z_j(t) − root(t)), j below k: the joints
whose path contains bone k. A ridge of `ridge` joint-frames pulls every v toward its current value (a bone whose
joints are never observed keeps it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from kinect_agent import skeleton
from kinect_agent.body import kinematics as km

N_V = km.N_BONES + 1  # bone vectors: index 0 the ROOT offset, k + 1 bone k


def _paths() -> tuple[np.ndarray, np.ndarray]:
    """Returns (below (N_V, J) bool: joint j's position depends on vector i, depth (N_V,) int)."""
    below = np.zeros((N_V, skeleton.J), dtype=bool)
    below[0] = True
    for j in range(1, skeleton.J):
        c = j
        while c > 0:
            below[c, j] = True  # vector c = bone c − 1, whose child is joint c
            c = int(skeleton.PARENT[c])
    depth = np.zeros(N_V, dtype=int)
    for c in range(1, skeleton.J):
        depth[c] = depth[int(skeleton.PARENT[c])] + 1
    return below, depth


BELOW, DEPTH = _paths()
# Pairs (i, d) with d on a path through i and at least as deep (A's non-zero blocks, i ≤ d in the tree).
PAIRS: tuple[tuple[int, int], ...] = tuple(
    (i, d) for d in range(N_V) for i in range(N_V) if (BELOW[d] <= BELOW[i]).all()
)
GROUP = np.concatenate(([0], km.BONE_GROUP))  # rotation group of each vector's frame
# The ROOT offset and the bones leaving ROOT (SPINE, HIP_L, HIP_R: the rigid pelvis group).
ROOT_GROUP = np.array([0, *(k + 1 for k, (p, _) in enumerate(skeleton.BONES) if p == 0)])
# Those and the bones leaving NECK (HEAD, SHO_L, SHO_R: the rigid shoulder group).
_NECK = skeleton.INDEX["NECK"]
RIGID_GROUPS = np.concatenate((ROOT_GROUP, [k + 1 for k, (p, _) in enumerate(skeleton.BONES) if p == _NECK]))


@dataclass
class Refit:
    """Result. model: a ChainModel with the new rest directions (same references). lengths (19,) m. root (T, 3) m
    (the ROOT offset folded in). shift_mm (19,): how far each bone vector moved, mm."""

    model: km.ChainModel
    lengths: np.ndarray
    root: np.ndarray
    shift_mm: np.ndarray


def refit_bones(
    model: km.ChainModel,
    root: np.ndarray,
    lengths: np.ndarray,
    theta: np.ndarray,
    z: np.ndarray,
    weights: np.ndarray,
    ridge: float = 1.0,
    max_change: float = 0.5,
    vectors: np.ndarray | None = None,
) -> Refit:
    """Returns the least-squares bone vectors given the rotations theta and the root.

    model: the chain of theta. root: (T, 3) m, camera frame. lengths: (19,) m. theta: (T, 33) rad.
    z: (T, J, 3) m, camera frame, the measurements (NaN where weights is 0). weights: (T, J) ≥ 0, 0 = not observed
    (e.g. 1 tracked, (σ_tracked/σ_inferred)² inferred). ridge: joint-frames of pull toward the current vectors.
    vectors: indices of the vectors re-fitted (0 the ROOT offset, k + 1 bone k; None: all); the others stay.
    max_change: a bone whose new length differs from the old by more than this fraction keeps its old vector.
    """
    T = len(theta)
    if z.shape != (T, skeleton.J, 3) or weights.shape != (T, skeleton.J) or root.shape != (T, 3):
        raise ValueError(f"expected z (T, J, 3), weights (T, J), root (T, 3) with T={T}; got "
                         f"{z.shape}, {weights.shape}, {root.shape}")  # fmt: skip
    G = model.global_rotations(model.local_rotations(theta))  # (T, 15, 3, 3) group frame -> camera
    w = np.where(np.all(np.isfinite(z), axis=-1), weights, 0.0)
    y = np.where(w[..., None] > 0, z - root[:, None, :], 0.0) * w[..., None]  # (T, J, 3)
    S = w @ BELOW.T.astype(float)  # (T, N_V): weight below each vector
    Y = np.einsum("tja,ij->tia", y, BELOW.astype(float))  # (T, N_V, 3)
    v0 = np.vstack((np.zeros(3), model.rest * lengths[:, None]))  # (N_V, 3)
    A = np.zeros((N_V, 3, N_V, 3))
    b = np.zeros((N_V, 3))
    Gv = G[:, GROUP]  # (T, N_V, 3, 3)
    for i, d in PAIRS:
        block = np.einsum("t,tai,taj->ij", S[:, d], Gv[:, i], Gv[:, d])
        A[i, :, d, :] += block
        if i != d:
            A[d, :, i, :] += block.T
    b += np.einsum("tvai,tva->vi", Gv, Y)
    A = A.reshape(3 * N_V, 3 * N_V) + ridge * np.eye(3 * N_V)
    rhs = b.reshape(-1) + ridge * v0.reshape(-1)
    free = np.ones(N_V, dtype=bool) if vectors is None else np.isin(np.arange(N_V), vectors)
    f3 = np.repeat(free, 3)
    v_flat = v0.reshape(-1).copy()
    v_flat[f3] = np.linalg.solve(A[np.ix_(f3, f3)], rhs[f3] - A[np.ix_(f3, ~f3)] @ v_flat[~f3])
    v = v_flat.reshape(N_V, 3)
    new_len = np.linalg.norm(v[1:], axis=1)
    keep = ~(np.abs(new_len - lengths) <= max_change * lengths)
    v[1:][keep] = v0[1:][keep]
    new_len = np.linalg.norm(v[1:], axis=1)
    refit_model = km.ChainModel(v[1:] / new_len[:, None], model.R_ref.copy(), compiled=model.compiled)
    new_root = root + np.einsum("tab,b->ta", G[:, 0], v[0])
    return Refit(refit_model, new_len, new_root, 1e3 * np.linalg.norm(v[1:] - v0[1:], axis=1))


__all__ = ["Refit", "refit_bones"]
