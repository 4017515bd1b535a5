"""Compiled kernels of the outlier model (outliers.py), used when numba is installed; numpy stays reference and
fallback, and tests hold both to the same results bit for bit (to 1e-12 relative for the mixture's fit where numpy
uses its own AVX-512 exp and log).

Each kernel does the same floating-point operations in the same order as the numpy expression it replaces (numpy
reduces a non-contiguous axis, and einsum its summed index, one term after the other; a reduction over a short
contiguous axis of 3 runs left to right), without the temporaries: no fused multiply-add, no reassociation
(no fastmath). Compiled on first use and cached on disk (numba cache=True), as _ukf_numba.py.
"""

from __future__ import annotations

import math
from typing import TypeAlias

import numpy as np
from numpy.typing import NDArray

from kinect_agent.numba_cache import cache_for, numba

AVAILABLE = numba is not None
CACHE = AVAILABLE and cache_for(__file__)  # numba's on-disk cache, or none (kinect_agent.numba_cache)
Floats: TypeAlias = NDArray[np.float64]
Ints: TypeAlias = NDArray[np.int64]
Bools: TypeAlias = NDArray[np.bool_]


def _insert_sorted(win: Floats, cnt: int, v: float) -> int:  # pragma: no cover - compiled
    """Inserts v into win[:cnt] (sorted ascending, ties after the equal values) and returns the new count."""
    j = cnt
    while j > 0 and win[j - 1] > v:
        win[j] = win[j - 1]
        j -= 1
    win[j] = v
    return cnt + 1


def _running_median(pad: Floats, w: int, out: Floats) -> None:  # pragma: no cover - compiled
    """out[m, t] = median of the finite values of pad[m, t : t + w] (NaN when none), as outliers.running_median.

    pad: (M, T + w − 1) float, NaN = missing; out: (M, T). The window is kept sorted from one frame to the next.
    """
    M, T = out.shape
    win = np.empty(w)
    for m in range(M):
        cnt = 0
        for i in range(w):
            v = pad[m, i]
            if v == v:  # finite values in sorted order at the front
                cnt = _insert_sorted(win, cnt, v)
        for t in range(T):
            if cnt > 0:
                out[m, t] = 0.5 * (win[(cnt - 1) // 2] + win[cnt // 2])
            else:
                out[m, t] = np.nan
            if t + 1 == T:
                break
            old, new = pad[m, t], pad[m, t + w]
            if old == old:  # remove the leaving value
                j = 0
                while win[j] != old:
                    j += 1
                while j < cnt - 1:
                    win[j] = win[j + 1]
                    j += 1
                cnt -= 1
            if new == new:  # insert the entering one
                cnt = _insert_sorted(win, cnt, new)


def _em_expectation(
    xz: Floats, ok: Bools, cls: Ints, rho: Floats, mu: Floats, sigma: Floats, norm: Floats, vol: Floats, w: Floats,
    rho_sum: Floats, mu_sum: Floats
) -> tuple[Floats, Floats]:  # pragma: no cover - compiled  # fmt: skip
    """One E step of outliers.fit_mixture with the sums of its M step; returns (loglik sum (K,), Σw (K,)).

    xz: (N, K, D) samples (0 where absent). ok: (N, K) bool present. cls: (N, K) int class (−1: none, weight 0).
    rho: (C, K) weights. mu, sigma: (K, D). norm: (K,) prod(σ)·√(2π)^D. vol: (K,) uniform box volume.
    Writes w (N, K) the Gaussian responsibilities, rho_sum (C, K) Σ w per class, mu_sum (K, D) Σ w·x.
    """
    N, K, D = xz.shape
    ll = np.zeros(K)
    sw = np.zeros(K)
    rho_sum[:] = 0.0
    mu_sum[:] = 0.0
    for n in range(N):
        for k in range(K):
            if not ok[n, k]:
                w[n, k] = 0.0
                continue
            c = cls[n, k]
            r = rho[c, k] if c >= 0 else 0.0
            zz = 0.0
            for d in range(D):
                q = (xz[n, k, d] - mu[k, d]) / sigma[k, d]
                if d == 0:
                    zz = q * q
                else:
                    zz = zz + q * q
            g = r * (math.exp(-0.5 * zz) / norm[k])
            u = (1.0 - r) / vol[k]
            tot = g + u
            if tot > 0:
                wk = g / tot
                ll[k] += math.log(tot)
            else:
                wk = g / 1.0
                ll[k] += math.log(1e-300)
            w[n, k] = wk
            sw[k] += wk
            if c >= 0:
                rho_sum[c, k] += wk
            for d in range(D):
                mu_sum[k, d] += wk * xz[n, k, d]
    return ll, sw


def _em_spread(xz: Floats, ok: Bools, w: Floats, mu: Floats, var_sum: Floats) -> None:  # pragma: no cover - compiled
    """var_sum (K, D) = Σ_n w·(x − mu)², as outliers.fit_mixture's M step (absent samples add exact zeros)."""
    N, K, D = xz.shape
    var_sum[:] = 0.0
    for n in range(N):
        for k in range(K):
            if ok[n, k]:
                for d in range(D):
                    q = xz[n, k, d] - mu[k, d]
                    var_sum[k, d] += w[n, k] * (q * q)


if AVAILABLE:
    _jit = numba.njit(cache=CACHE, nogil=True, error_model="numpy")
    _insert_sorted = _jit(_insert_sorted)  # called by _running_median: compiled before it
    running_median_kernel = _jit(_running_median)
    em_expectation = _jit(_em_expectation)
    em_spread = _jit(_em_spread)
else:  # pragma: no cover - callers check AVAILABLE first
    running_median_kernel = em_expectation = em_spread = None  # type: ignore[assignment]


def _window_sums(
    wp: Floats, yp: Floats, kern: Floats, powers: Floats, S: Floats, S2: Floats, B: Floats
) -> None:  # pragma: no cover - compiled
    """The kernel-weighted window sums of outliers.local_quadratic, Wk = wp[t + i, j]·kern[t, i]:
    S[t, j, m] = Σ_i Wk·powers[t, i, m], S2 = Σ_i (Wk·Wk)·powers, B[t, j, m, a] = Σ_i (yp[t + i, j, a]·Wk)·powers
    (m < 3), each summed over i in order.

    wp: (T + w − 1, J) weights, yp: (T + w − 1, J, 3) m (0 where absent), kern: (T, w), powers: (T, w, 5).
    Each sum runs from 0 over i = 0, 1, ..., w − 1 as before; the joints are the innermost loop (J independent sums
    side by side in contiguous accumulators), so that it vectorises without reordering any sum.
    """
    T, J, M = S.shape
    w = kern.shape[1]
    yt = np.empty((yp.shape[0], 3, J))  # yp with the joints last (contiguous)
    for r in range(yp.shape[0]):
        for a in range(3):
            for j in range(J):
                yt[r, a, j] = yp[r, j, a]
    wk = np.empty(J)
    s = np.empty((M, J))
    s2 = np.empty((M, J))
    b = np.empty((3, 3, J))
    for t in range(T):
        s[:, :] = 0.0
        s2[:, :] = 0.0
        b[:, :, :] = 0.0
        for i in range(w):
            kt = kern[t, i]
            for j in range(J):
                wk[j] = wp[t + i, j] * kt
            for m in range(M):
                p = powers[t, i, m]
                for j in range(J):
                    s[m, j] += wk[j] * p
                    s2[m, j] += (wk[j] * wk[j]) * p
            for m in range(3):
                p = powers[t, i, m]
                for a in range(3):
                    for j in range(J):
                        b[m, a, j] += (yt[t + i, a, j] * wk[j]) * p
        for j in range(J):
            for m in range(M):
                S[t, j, m] = s[m, j]
                S2[t, j, m] = s2[m, j]
            for m in range(3):
                for a in range(3):
                    B[t, j, m, a] = b[m, a, j]


def _quadratic_at_centre(
    coef: Floats, S2: Floats, B: Floats, pred: Floats, lev: Floats
) -> None:  # pragma: no cover - compiled
    """pred[t, j, a] = Σ_m coef[t, j, m]·B[t, j, m, a] and lev[t, j] = Σ_m Σ_n (coef_m·S2[t, j, m + n])·coef_n, each
    summed in order, as outliers.local_quadratic's einsums."""
    T, J, _ = coef.shape
    for t in range(T):
        for j in range(J):
            for a in range(3):
                p = 0.0
                for m in range(3):
                    p += coef[t, j, m] * B[t, j, m, a]
                pred[t, j, a] = p
            v = 0.0
            for m in range(3):
                for n in range(3):
                    v += (coef[t, j, m] * S2[t, j, m + n]) * coef[t, j, n]
            lev[t, j] = v


if AVAILABLE:
    window_sums = _jit(_window_sums)
    quadratic_at_centre = _jit(_quadratic_at_centre)
else:  # pragma: no cover - callers check AVAILABLE first
    window_sums = quadratic_at_centre = None  # type: ignore[assignment]
