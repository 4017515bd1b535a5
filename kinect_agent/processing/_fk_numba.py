"""Compiled kernels of the kinematic UKF, used when numba is installed (numpy versions stay reference and fallback).

fk_many: forward kinematics of ChainModel for many states at once (sigma points), same mathematics as
ChainModel.positions_numpy. chain_update: one gated UKF update of the chain state, same mathematics as
ukf.gated_update with hx = the chain (tests check both against their numpy versions). Compiled on first use (about
10 s) and cached on disk (numba cache=True).
"""

from __future__ import annotations

import numpy as np

try:
    import numba
except ImportError:  # pragma: no cover - exercised only where numba is absent
    numba = None

AVAILABLE = numba is not None


def _fk_many(root, lengths, theta, rest, R_ref, rot_dof, rot_start, rot_parent, ref_index, second_axis,
             bone_parent, bone_group, out):  # fmt: skip
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


fk_many = numba.njit(cache=True, fastmath=False, nogil=True)(_fk_many) if AVAILABLE else None


def _chain_update(x, P, scale, Wm0, Wm1, Wc0, Wc1, z, groups, R_diag, gate, fixed_lengths, n_len,
                  rest, R_ref, rot_dof, rot_start, rot_parent, ref_index, second_axis, bone_parent, bone_group,
                  used):  # fmt: skip
    """One gated UKF update of the chain state, compiled (same mathematics as ukf.gated_update).

    x (n,), P (n, n) are updated in place. State layout: root (3), lengths (n_len = 19, or 0 when fixed_lengths
    holds them), theta (33). z (60,) m; groups (20,) bool observed joints; R_diag (60,) m²; used (20,) bool out.
    """
    n = x.shape[0]
    J = groups.shape[0]
    L = np.linalg.cholesky(P)
    S_n = 2 * n + 1
    root = np.empty((S_n, 3))
    lengths = np.empty((S_n, fixed_lengths.shape[0]))
    theta = np.empty((S_n, n - 3 - n_len))
    for s in range(S_n):
        for i in range(n):
            v = x[i]
            if s >= 1 and s <= n:
                v += scale * L[i, s - 1]
            elif s > n:
                v -= scale * L[i, s - n - 1]
            if i < 3:
                root[s, i] = v
            elif i < 3 + n_len:
                lengths[s, i - 3] = v
            else:
                theta[s, i - 3 - n_len] = v
        if n_len == 0:
            for k in range(fixed_lengths.shape[0]):
                lengths[s, k] = fixed_lengths[k]
    pos = np.empty((S_n, J, 3))
    _fk_core(root, lengths, theta, rest, R_ref, rot_dof, rot_start, rot_parent, ref_index, second_axis,
             bone_parent, bone_group, pos)  # fmt: skip
    g = 0
    for j in range(J):
        if groups[j]:
            g += 1
    m = 3 * g
    Z = np.empty((S_n, m))
    zo = np.empty(m)
    Ro = np.empty(m)
    c = 0
    for j in range(J):
        if groups[j]:
            for a in range(3):
                zo[c] = z[3 * j + a]
                Ro[c] = R_diag[3 * j + a]
                for s in range(S_n):
                    Z[s, c] = pos[s, j, a]
                c += 1
    zp = Wm0 * Z[0].copy()
    for s in range(1, S_n):
        zp += Wm1 * Z[s]
    dz = Z - zp
    tail = np.ascontiguousarray(dz[1:])
    S = Wc1 * np.dot(tail.T, tail)
    for a in range(m):
        for b in range(m):
            S[a, b] += Wc0 * dz[0, a] * dz[0, b]
        S[a, a] += Ro[a]
    y = zo - zp
    ok = np.zeros(g, dtype=np.bool_)
    for k in range(g):
        b = 3 * k
        a00, a01, a02 = S[b, b], S[b, b + 1], S[b, b + 2]
        a11, a12, a22 = S[b + 1, b + 1], S[b + 1, b + 2], S[b + 2, b + 2]
        c00 = a11 * a22 - a12 * a12
        c01 = a02 * a12 - a01 * a22
        c02 = a01 * a12 - a02 * a11
        c11 = a00 * a22 - a02 * a02
        c12 = a01 * a02 - a00 * a12
        c22 = a00 * a11 - a01 * a01
        det = a00 * c00 + a01 * c01 + a02 * c02
        y0, y1, y2 = y[b], y[b + 1], y[b + 2]
        d2 = (y0 * (c00 * y0 + c01 * y1 + c02 * y2) + y1 * (c01 * y0 + c11 * y1 + c12 * y2)
              + y2 * (c02 * y0 + c12 * y1 + c22 * y2)) / det  # fmt: skip
        ok[k] = d2 <= gate
    k = 0
    for j in range(J):
        used[j] = False
        if groups[j]:
            used[j] = ok[k]
            k += 1
    kept = 0
    for k in range(g):
        if ok[k]:
            kept += 1
    if kept == 0:
        return
    mk = 3 * kept
    idx = np.empty(mk, dtype=np.int64)
    c = 0
    for k in range(g):
        if ok[k]:
            for a in range(3):
                idx[c] = 3 * k + a
                c += 1
    Sk = np.empty((mk, mk))
    for a in range(mk):
        for b in range(mk):
            Sk[a, b] = S[idx[a], idx[b]]
    D = np.empty((n, mk))
    for i in range(n):
        for a in range(mk):
            D[i, a] = dz[1 + i, idx[a]] - dz[1 + n + i, idx[a]]
    Pxz = (scale * Wc1) * np.dot(L, D)
    Kt = np.linalg.solve(Sk, np.ascontiguousarray(Pxz.T))  # (mk, n)
    yk = np.empty(mk)
    for a in range(mk):
        yk[a] = y[idx[a]]
    x += np.dot(yk, Kt)
    Pn = P - np.dot(Pxz, Kt)
    for i in range(n):
        for j2 in range(n):
            P[i, j2] = 0.5 * (Pn[i, j2] + Pn[j2, i])


if AVAILABLE:
    _fk_core = fk_many
    chain_update = numba.njit(cache=True, nogil=True)(_chain_update)
else:  # pragma: no cover
    chain_update = None
