"""Compiled forward kinematics, used when numba is installed (the numpy version stays reference and fallback).

fk_many: forward kinematics of ChainModel for many states at once, same mathematics as
ChainModel.positions_numpy (tests check both agree). The fused UKF update lives in _ukf_numba.py. Compiled on first
use and cached on disk (numba cache=True).
"""

from __future__ import annotations

from typing import TypeAlias

import numpy as np
from numpy.typing import NDArray

from kinect_agent.numba_cache import cache_for, numba

AVAILABLE = numba is not None
CACHE = AVAILABLE and cache_for(__file__)  # numba's on-disk cache, or none (kinect_agent.numba_cache)
Floats: TypeAlias = NDArray[np.float64]
Ints: TypeAlias = NDArray[np.int64]


def _fk_many(root: Floats, lengths: Floats, theta: Floats, rest: Floats, R_ref: Floats, rot_dof: Ints, rot_start: Ints,
             rot_parent: Ints, ref_index: Ints, second_axis: Ints, bone_parent: Ints, bone_group: Ints,
             out: Floats) -> None:  # fmt: skip
    S = root.shape[0]
    n_rot = rot_dof.shape[0]
    n_bones = bone_parent.shape[0]
    G = np.empty((n_rot, 3, 3))
    L = np.empty((3, 3))
    for s in range(S):
        for r in range(n_rot):
            i = rot_start[r]
            d = rot_dof[r]
            if d == 3:
                x, y, z = theta[s, i], theta[s, i + 1], theta[s, i + 2]
                th2 = x * x + y * y + z * z
                if th2 < 1e-12:
                    a = 1.0 - th2 / 6.0
                    b = 0.5 - th2 / 24.0
                else:
                    th = np.sqrt(th2)
                    a = np.sin(th) / th
                    b = (1.0 - np.cos(th)) / th2
                E00 = 1.0 - b * (y * y + z * z)
                E11 = 1.0 - b * (x * x + z * z)
                E22 = 1.0 - b * (x * x + y * y)
                E01, E10 = b * x * y - a * z, b * x * y + a * z
                E02, E20 = b * x * z + a * y, b * x * z - a * y
                E12, E21 = b * y * z - a * x, b * y * z + a * x
                F = R_ref[ref_index[r]]
                for u in range(3):
                    L[u, 0] = F[u, 0] * E00 + F[u, 1] * E10 + F[u, 2] * E20
                    L[u, 1] = F[u, 0] * E01 + F[u, 1] * E11 + F[u, 2] * E21
                    L[u, 2] = F[u, 0] * E02 + F[u, 1] * E12 + F[u, 2] * E22
            elif d == 1:
                c, sn = np.cos(theta[s, i]), np.sin(theta[s, i])
                L[0, 0], L[0, 1], L[0, 2] = 1.0, 0.0, 0.0
                L[1, 0], L[1, 1], L[1, 2] = 0.0, c, -sn
                L[2, 0], L[2, 1], L[2, 2] = 0.0, sn, c
            else:
                ca, sa = np.cos(theta[s, i]), np.sin(theta[s, i])
                cb, sb = np.cos(theta[s, i + 1]), np.sin(theta[s, i + 1])
                if second_axis[r] == 2:
                    L[0, 0], L[0, 1], L[0, 2] = cb, -sb, 0.0
                    L[1, 0], L[1, 1], L[1, 2] = ca * sb, ca * cb, -sa
                    L[2, 0], L[2, 1], L[2, 2] = sa * sb, sa * cb, ca
                else:
                    L[0, 0], L[0, 1], L[0, 2] = cb, 0.0, sb
                    L[1, 0], L[1, 1], L[1, 2] = sa * sb, ca, -sa * cb
                    L[2, 0], L[2, 1], L[2, 2] = -ca * sb, sa, ca * cb
            p = rot_parent[r]
            if p < 0:
                for u in range(3):
                    for v in range(3):
                        G[r, u, v] = L[u, v]
            else:
                for u in range(3):
                    for v in range(3):
                        G[r, u, v] = G[p, u, 0] * L[0, v] + G[p, u, 1] * L[1, v] + G[p, u, 2] * L[2, v]
        out[s, 0, 0], out[s, 0, 1], out[s, 0, 2] = root[s, 0], root[s, 1], root[s, 2]
        for k in range(n_bones):
            g = bone_group[k]
            p = bone_parent[k]
            ln = lengths[s, k]
            for u in range(3):
                out[s, k + 1, u] = out[s, p, u] + ln * (
                    G[g, u, 0] * rest[k, 0] + G[g, u, 1] * rest[k, 1] + G[g, u, 2] * rest[k, 2]
                )


if AVAILABLE:
    fk_many = numba.njit(cache=CACHE, fastmath=False, nogil=True)(_fk_many)
else:  # pragma: no cover - callers check AVAILABLE first
    fk_many = None  # type: ignore[assignment]
