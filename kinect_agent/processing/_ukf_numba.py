"""The fused, compiled UKF update of the kinematic chain: sigma points, forward kinematics, innovation statistics,
per-joint gate and the Kalman correction in one numba kernel (same mathematics as UnscentedKalmanFilter.gated_update
with hx = the chain, which stays the reference; tests check both agree to 1e-9).

Structure used for speed (results equal the plain computation to rounding):
- σ = x ± c·L_i with L the lower Cholesky factor of P, so σ differs from x only in state entries >= i. Joint
  rotations whose angles all come before entry i are therefore those of x, and so are the positions of joints
  whose chain above them holds only such rotations; they are copied from the centre point, not recomputed.
- Innovation covariance and P's correction by symmetric rank-k updates (dsyrk), the gain by one Cholesky
  factorisation of the kept rows' innovation covariance and one triangular solve (LAPACK, see _blas_numba.py).
- Sigma points are the last (contiguous) axis of the kernel's arrays, so its loops over them vectorise; sin/cos
  are a branch-free polynomial (_sincos) for the same reason.
- Missing and gated joints are index lists inside the kernel; nothing is re-indexed or copied in Python.

Only defined when numba is installed (AVAILABLE).
"""

from __future__ import annotations

from typing import TypeAlias

import numpy as np
from numpy.typing import NDArray

from kinect_agent.numba_cache import cache_for, numba
from kinect_agent.processing import _blas_numba

AVAILABLE = numba is not None and _blas_numba.AVAILABLE
CACHE = AVAILABLE and cache_for(__file__)  # numba's on-disk cache, or none (kinect_agent.numba_cache)
Floats: TypeAlias = NDArray[np.float64]
Ints: TypeAlias = NDArray[np.int64]
Bools: TypeAlias = NDArray[np.bool_]
# run_frames' groups of arguments (see its docstring)
Observations: TypeAlias = tuple[Floats, Bools, Floats, Bools, Ints, Bools]
Noise: TypeAlias = tuple[Floats, Ints, Floats]
StepKernel: TypeAlias = tuple[Floats, float, Floats, int, Floats, Floats, Ints]
Restart: TypeAlias = tuple[Floats, int, Ints]

# Rows of the packed table `tabs` (int64, (9, 33)) given to chain_step; see kinematics.STEP_TABLES.
ROT_DOF, ROT_START, ROT_PARENT, REF_INDEX, SECOND_AXIS, BONE_PARENT, BONE_GROUP, THETA_ROT, JOINT_LAST_ROT = range(9)
OK, P_NOT_POSITIVE, S_NOT_POSITIVE = 0, 1, 2  # chain_step's status


def _sincos(x: float) -> tuple[float, float]:  # pragma: no cover - compiled
    """Returns (sin x, cos x) to within 1 ulp of libm: Cody-Waite reduction by π/2 and fdlibm's kernels.

    Branch-free, so loops over sigma points vectorise (libm's sin/cos are scalar calls).
    """
    k = np.floor(x * 0.63661977236758134308 + 0.5)
    r = ((x - k * 1.57079632673412561417e00) - k * 6.07710050630396597660e-11) - k * 2.02226624871116645580e-21
    z = r * r
    s = r + r * z * (-1.66666666666666324348e-01 + z * (8.33333333332248946124e-03 + z * (
        -1.98412698298579493134e-04 + z * (2.75573137070700676789e-06 + z * (
            -2.50507602534068634195e-08 + z * 1.58969099521155010221e-10)))))  # fmt: skip
    hz = 0.5 * z
    w = 1.0 - hz
    c = w + (((1.0 - w) - hz) + z * z * (4.16666666666666019037e-02 + z * (-1.38888888888741095749e-03 + z * (
        2.48015872894767294178e-05 + z * (-2.75573143513906633035e-07 + z * (
            2.08757232129817482790e-09 + z * -1.13596475577881948265e-11))))))  # fmt: skip
    q = k - 4.0 * np.floor(k * 0.25)
    sn = s if q == 0.0 else (c if q == 1.0 else (-s if q == 2.0 else -c))
    cs = c if q == 0.0 else (-s if q == 1.0 else (-c if q == 2.0 else s))
    return sn, cs


def _compose(G: Floats, r: int, p: int, s: int, l00: float, l01: float, l02: float, l10: float, l11: float,
             l12: float, l20: float, l21: float, l22: float) -> None:  # pragma: no cover - compiled  # fmt: skip
    """G[r, :, :, s] = G[p, :, :, s] · L, L given by its 9 entries (p may be the identity slot: no branch here,
    so loops over s vectorise)."""
    for u in range(3):
        g0, g1, g2 = G[p, u, 0, s], G[p, u, 1, s], G[p, u, 2, s]
        G[r, u, 0, s] = g0 * l00 + g1 * l10 + g2 * l20
        G[r, u, 1, s] = g0 * l01 + g1 * l11 + g2 * l21
        G[r, u, 2, s] = g0 * l02 + g1 * l12 + g2 * l22


def _sigma_positions(x: Floats, Lc: Floats, scale: float, n_len: int, fixed_lengths: Floats, rest: Floats,
                     R_ref: Floats, tabs: Ints, pos: Floats) -> None:  # pragma: no cover - compiled  # fmt: skip
    """Writes the joint positions pos (J, 3, 2n+1) m of the sigma points in the order x, x + c·L_0, x − c·L_0,
    x + c·L_1, x − c·L_1, ... (sigma point index last, so that loops over sigma points vectorise).

    x (n,) = root (3), lengths (n_len), theta; Lc (n, n) lower Cholesky factor, zero above the diagonal. Column i
    moves only state entries >= i, so a rotation or joint that entry i cannot reach is the centre's for the
    points of columns >= i: each is computed for a prefix of the points and copied from the centre for the rest.
    """
    n = x.shape[0]
    S = 2 * n + 1
    n_rot = 15
    n_bones = rest.shape[0]
    off = 3 + n_len
    val = np.empty((n, S))  # state of every sigma point, entry-major
    for i in range(n):
        xi = x[i]
        val[i, 0] = xi
        for col in range(n):
            d = scale * Lc[i, col]
            val[i, 1 + 2 * col] = xi + d
            val[i, 2 + 2 * col] = xi - d
    ln = np.empty((n_bones, S))
    for k in range(n_bones):
        for s in range(S):
            ln[k, s] = val[3 + k, s] if k < n_len else fixed_lengths[k]
    ab = np.empty((2, S))  # Rodrigues coefficients of one 3-DoF rotation for every point (own loop: vectorises)
    G = np.empty((n_rot + 1, 3, 3, S))  # slot n_rot: the identity, "parent" of the root rotation
    for u in range(3):
        for v in range(3):
            for s in range(S):
                G[n_rot, u, v, s] = 1.0 if u == v else 0.0
    for r in range(n_rot):
        i = off + tabs[ROT_START, r]
        d = tabs[ROT_DOF, r]
        p = tabs[ROT_PARENT, r] if tabs[ROT_PARENT, r] >= 0 else n_rot
        cnt = min(S, 1 + 2 * (i + d))  # points whose perturbation reaches this rotation
        if d == 3:
            F = R_ref[tabs[REF_INDEX, r]]
            f00, f01, f02, f10, f11, f12 = F[0, 0], F[0, 1], F[0, 2], F[1, 0], F[1, 1], F[1, 2]
            f20, f21, f22 = F[2, 0], F[2, 1], F[2, 2]
            for s in range(cnt):  # Rodrigues coefficients a = sin θ / θ, b = (1 − cos θ) / θ² (series near 0)
                vx, vy, vz = val[i, s], val[i + 1, s], val[i + 2, s]
                th2 = vx * vx + vy * vy + vz * vz
                small = th2 < 1e-12
                t = np.sqrt(th2)
                sn, cs = _sincos_c(t)
                ab[0, s] = 1.0 - th2 / 6.0 if small else sn / (1.0 if small else t)
                ab[1, s] = 0.5 - th2 / 24.0 if small else (1.0 - cs) / (1.0 if small else th2)
            for s in range(cnt):
                vx, vy, vz = val[i, s], val[i + 1, s], val[i + 2, s]
                a, b = ab[0, s], ab[1, s]
                E00 = 1.0 - b * (vy * vy + vz * vz)
                E11 = 1.0 - b * (vx * vx + vz * vz)
                E22 = 1.0 - b * (vx * vx + vy * vy)
                E01, E10 = b * vx * vy - a * vz, b * vx * vy + a * vz
                E02, E20 = b * vx * vz + a * vy, b * vx * vz - a * vy
                E12, E21 = b * vy * vz - a * vx, b * vy * vz + a * vx
                _compose_c(G, r, p, s,
                           f00 * E00 + f01 * E10 + f02 * E20, f00 * E01 + f01 * E11 + f02 * E21,
                           f00 * E02 + f01 * E12 + f02 * E22, f10 * E00 + f11 * E10 + f12 * E20,
                           f10 * E01 + f11 * E11 + f12 * E21, f10 * E02 + f11 * E12 + f12 * E22,
                           f20 * E00 + f21 * E10 + f22 * E20, f20 * E01 + f21 * E11 + f22 * E21,
                           f20 * E02 + f21 * E12 + f22 * E22)  # fmt: skip
        elif d == 1:
            for s in range(cnt):
                sn, c = _sincos_c(val[i, s])
                _compose_c(G, r, p, s, 1.0, 0.0, 0.0, 0.0, c, -sn, 0.0, sn, c)
        elif tabs[SECOND_AXIS, r] == 2:
            for s in range(cnt):
                sa, ca = _sincos_c(val[i, s])
                sb, cb = _sincos_c(val[i + 1, s])
                _compose_c(G, r, p, s, cb, -sb, 0.0, ca * sb, ca * cb, -sa, sa * sb, sa * cb, ca)
        else:
            for s in range(cnt):
                sa, ca = _sincos_c(val[i, s])
                sb, cb = _sincos_c(val[i + 1, s])
                _compose_c(G, r, p, s, cb, 0.0, sb, sa * sb, ca, -sa * cb, -ca * sb, sa, ca * cb)
        for u in range(3):
            for v in range(3):
                g = G[r, u, v, 0]
                for s in range(cnt, S):
                    G[r, u, v, s] = g
    for a in range(3):
        for s in range(S):
            pos[0, a, s] = val[a, s]
    for k in range(n_bones):
        c = k + 1
        g = tabs[BONE_GROUP, k]
        p = tabs[BONE_PARENT, k]
        last = tabs[JOINT_LAST_ROT, c]
        cnt = min(S, 1 + 2 * (off + tabs[ROT_START, last] + tabs[ROT_DOF, last]))
        r0, r1, r2 = rest[k, 0], rest[k, 1], rest[k, 2]
        lk = fixed_lengths[k]
        for u in range(3):
            if k < n_len:  # length varies over the points
                for s in range(cnt):
                    pos[c, u, s] = pos[p, u, s] + ln[k, s] * (
                        G[g, u, 0, s] * r0 + G[g, u, 1, s] * r1 + G[g, u, 2, s] * r2
                    )
            else:  # fixed length: a loop over two arrays only, which vectorises
                for s in range(cnt):
                    pos[c, u, s] = pos[p, u, s] + lk * (G[g, u, 0, s] * r0 + G[g, u, 1, s] * r1 + G[g, u, 2, s] * r2)
            q = pos[c, u, 0]
            for s in range(cnt, S):
                pos[c, u, s] = q


def _chain_step(x: Floats, P: Floats, z: Floats, observed: Bools, R_diag: Floats, w: Floats, gate: float,
                fixed_lengths: Floats, n_len: int, rest: Floats, R_ref: Floats, tabs: Ints,
                used: Bools) -> int:  # fmt: skip
    """One gated UKF update of the chain state (UnscentedKalmanFilter.gated_update, hx = the chain), in place.

    x (n,) = root (3) m, lengths (n_len = 19, or 0 when fixed_lengths (19,) m holds them), theta (33) rad;
    P (n, n). z (60,) m, NaN where missing; observed (60,) bool; R_diag (60,) m². w = (c, Wm0, Wm1, Wc0, Wc1) of
    the sigma points; gate: chi² limit of one joint's innovation d². used (20,) bool out: joints that entered.
    Returns OK, or P_NOT_POSITIVE / S_NOT_POSITIVE (then x, P are unchanged and the caller falls back to numpy).
    """
    n = x.shape[0]
    J = used.shape[0]
    scale, Wm0, Wm1, Wc0, Wc1 = w[0], w[1], w[2], w[3], w[4]
    at_mean = w.shape[0] > 5 and w[5] != 0.0
    gj = np.empty(J, dtype=np.int64)
    g = 0
    for j in range(J):
        used[j] = False
        good = True
        for a in range(3):
            if not observed[3 * j + a] or not np.isfinite(z[3 * j + a]):
                good = False
        if good:
            gj[g] = j
            g += 1
    if g == 0:
        return OK
    Lc = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            Lc[i, j] = P[i, j] if j <= i else 0.0
    if _blas_numba.cholesky_lower(Lc, n) != 0:
        return P_NOT_POSITIVE
    for i in range(n):
        for j in range(i + 1, n):
            Lc[i, j] = 0.0
    S_n = 2 * n + 1
    pos = np.empty((J, 3, S_n))
    _sigma_positions_c(x, Lc, scale, n_len, fixed_lengths, rest, R_ref, tabs, pos)
    m = 3 * g
    dz = np.empty((m, S_n))  # row c: observation c of every sigma point minus its mean
    y = np.empty(m)
    for q in range(g):
        j = gj[q]
        for a in range(3):
            c = 3 * q + a
            acc0 = acc1 = acc2 = acc3 = 0.0  # four partial sums: no serial dependence on one accumulator
            for s in range(1, S_n - 3, 4):
                acc0 += pos[j, a, s]
                acc1 += pos[j, a, s + 1]
                acc2 += pos[j, a, s + 2]
                acc3 += pos[j, a, s + 3]
            for s in range(S_n - (S_n - 1) % 4, S_n):
                acc0 += pos[j, a, s]
            mean = Wm0 * pos[j, a, 0] + Wm1 * ((acc0 + acc1) + (acc2 + acc3))
            y[c] = z[3 * j + a] - (pos[j, a, 0] if at_mean else mean)
            for s in range(S_n):
                dz[c, s] = pos[j, a, s] - mean
    S = np.empty((m, m))
    _blas_numba.gram_rows_lower(dz.reshape(m * S_n)[1:], m, S_n - 1, S_n, Wc1, S)
    for a in range(m):  # lower triangle only from here on
        wa = Wc0 * dz[a, 0]
        for b in range(a + 1):
            S[a, b] += wa * dz[b, 0]
        S[a, a] += R_diag[3 * gj[a // 3] + a % 3]
    keep = np.empty(m, dtype=np.int64)
    mk = 0
    for q in range(g):
        b = 3 * q
        a00, a01, a02 = S[b, b], S[b + 1, b], S[b + 2, b]
        a11, a12, a22 = S[b + 1, b + 1], S[b + 2, b + 1], S[b + 2, b + 2]
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
        if d2 <= gate:
            used[gj[q]] = True
            for a in range(3):
                keep[mk] = b + a
                mk += 1
    if mk == 0:
        return OK
    if mk == m:  # nothing gated: factorise S itself (it is not needed afterwards)
        Sk = S
    else:
        Sk = np.empty((mk, mk))
        for a in range(mk):
            for b in range(a + 1):
                Sk[a, b] = S[keep[a], keep[b]]
    if _blas_numba.cholesky_lower(Sk, mk) != 0:
        for j in range(J):
            used[j] = False
        return S_NOT_POSITIVE
    # Pxz = Σ Wc_i (σ_i − x) dz_iᵀ = c·Wc1·L (dz₊ − dz₋) since σ_i − x = ±c·L_i (the centre term is zero).
    Dt = np.empty((mk, n))  # (dz₊ − dz₋)ᵀ of the kept rows
    for a in range(mk):
        ka = keep[a]
        for i in range(n):
            Dt[a, i] = dz[ka, 1 + 2 * i] - dz[ka, 2 + 2 * i]
    PxzT = np.dot(Dt, Lc.T)
    # B = L_S⁻¹ [Pxzᵀ | y]: then x += B_nᵀ B_y and P −= B_nᵀ B_n (K = Pxz S⁻¹, S = L_S L_Sᵀ).
    B = np.empty((mk, n + 1))
    cw = scale * Wc1
    for a in range(mk):
        for i in range(n):
            B[a, i] = cw * PxzT[a, i]
        B[a, n] = y[keep[a]]
    _blas_numba.solve_lower(Sk, mk, B, mk, n + 1)
    Pn = np.empty((n, n))
    for i in range(n):
        for j in range(i + 1):
            Pn[i, j] = 0.5 * (P[i, j] + P[j, i])
    _blas_numba.gram_lower(B, mk, n, -1.0, 1.0, Pn)
    dx = np.zeros(n)
    for a in range(mk):
        ya = B[a, n]
        for i in range(n):
            dx[i] += B[a, i] * ya
    for i in range(n):
        x[i] += dx[i]
        for j in range(i + 1):
            P[i, j] = Pn[i, j]
            P[j, i] = Pn[i, j]
    return OK


def _add_capped(P: Floats, diag: Ints, q: Floats, ceiling: Floats) -> None:  # pragma: no cover - compiled
    """P[d, d] += min(q, max(ceiling − P[d, d], 0)) for d in diag (see chain_filter.ChainFilter.predict_random_walk)."""
    for i in range(diag.shape[0]):
        d = diag[i]
        P[d, d] += min(q[i], max(ceiling[i] - P[d, d], 0.0))


def _run_frames(
    x: Floats, P: Floats, x_prior: Floats, P_prior: Floats, obs: Observations, order: Ints, q_steps: Floats, i0: int,
    i1: int, noise: Noise, kern: StepKernel, restart: Restart, run: Ints, used: Bools, xs: Floats, Ps: Floats
) -> tuple[int, int]:  # pragma: no cover - compiled  # fmt: skip
    """Frames order[i0:i1] of one filter pass (pipeline._run_pass), in place: per frame the capped random-walk
    predict (add_capped with q = Q·q_steps[i], none for i = 0), the re-acquisition of lost joints, chain_step, the
    gate's bookkeeping, and x, P stored when xs has rows. The same operations as the pass's Python loop.

    obs = (z (T, 60) m, observed (T, 60) bool, R_diag (T, 60) m², present (T, J) bool, n_present (T,) int,
    any_observed (T,) bool).
    noise = (Q diagonal (n,), diag indices (n,), ceiling (n,)). kern = chain_step's (w, gate, fixed_lengths, n_len,
    rest, R_ref, tabs). restart = (start (T, 36) root m + theta rad, n_frames (0: never), placing (J, 36) int,
    -1 padded: the entries of root + theta that place each joint). run (J,) int: consecutive gated frames, updated.
    Returns (i, gated): i = i1 when done, or the index of a frame whose chain_step found a covariance that is not
    positive definite (x, P as before its update, x_prior and P_prior set; the caller updates it in numpy).
    """
    z, observed, R_diag, present, n_present, any_observed = obs
    qd, diag, ceiling = noise
    w, gate, fixed_lengths, n_len, rest, R_ref, tabs = kern
    start, restart_n, placing = restart
    n = x.shape[0]
    J = run.shape[0]
    n_th = start.shape[1]
    store = xs.shape[0] > 0
    gated = 0
    lost = np.zeros(J, dtype=np.bool_)
    mark = np.zeros(n_th, dtype=np.bool_)
    for i in range(i0, i1):
        k = order[i]
        if i:
            scale = q_steps[i]
            for m in range(diag.shape[0]):
                d = diag[m]
                P[d, d] += min(qd[m] * scale, max(ceiling[m] - P[d, d], 0.0))
        if any_observed[k]:
            if restart_n > 0:
                any_lost = False
                for j in range(J):
                    lost[j] = present[k, j] and run[j] >= restart_n
                    any_lost = any_lost or lost[j]
                if any_lost:
                    mark[:] = False
                    for j in range(J):
                        if lost[j]:
                            for c in range(placing.shape[1]):
                                if placing[j, c] >= 0:
                                    mark[placing[j, c]] = True
                    for e in range(n_th):
                        if mark[e]:
                            idx = e if e < 3 else e + n - n_th
                            x[idx] = start[k, e]
                            for c in range(n):
                                P[idx, c] = 0.0
                                P[c, idx] = 0.0
                    for e in range(n_th):
                        if mark[e]:
                            idx = e if e < 3 else e + n - n_th
                            P[idx, idx] = ceiling[idx]
                    for j in range(J):
                        if lost[j]:
                            run[j] = 0
            x_prior[:] = x
            P_prior[:, :] = P
            status = _chain_step_c(x, P, z[k], observed[k], R_diag[k], w, gate, fixed_lengths, n_len, rest, R_ref,
                                   tabs, used)  # fmt: skip
            if status != OK:
                return i, gated
            n_used = 0
            for j in range(J):
                if used[j]:
                    n_used += 1
                    run[j] = 0
                elif present[k, j]:
                    run[j] += 1
            gated += n_present[k] - n_used
        if store:
            xs[k, :] = x
            Ps[k, :, :] = P
    return i1, gated


if AVAILABLE:
    # error_model="numpy": no zero-division checks (loops stay vectorisable); "contract": fused multiply-adds.
    _jit = numba.njit(cache=CACHE, nogil=True, error_model="numpy", fastmath={"contract"})
    _inline = numba.njit(cache=CACHE, nogil=True, error_model="numpy", fastmath={"contract"}, inline="always")
    _sincos_c = _inline(_sincos)
    _compose_c = _inline(_compose)
    _sigma_positions_c = _jit(_sigma_positions)
    chain_step = _chain_step_c = _jit(_chain_step)
    add_capped = _jit(_add_capped)
    # The pass loop: no fastmath (the predict's product and sums as numpy does them); chain_step keeps its flags.
    run_frames = numba.njit(cache=CACHE, nogil=True, error_model="numpy")(_run_frames)
else:  # pragma: no cover - callers check AVAILABLE first
    chain_step = add_capped = run_frames = None  # type: ignore[assignment]
