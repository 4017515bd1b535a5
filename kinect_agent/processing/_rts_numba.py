"""The unscented RTS smoother of the random walk (ukf._rts_random_walk) in one compiled loop, used when numba is
installed and numpy's OpenBLAS is found (_blas_numba.NUMPY_BLAS); numpy stays the reference and the fallback, and
tests hold both to the same results bit for bit.

Each step does what the numpy loop does, in its order: the element-wise sums and products as numpy's ufuncs do them
(no fastmath, no fused multiply-add), the gain's factorisation and solve by the same LAPACK routines of SciPy's
OpenBLAS with the arrays SciPy's wrappers would pass (dpotrf, dpotrs on Fortran copies), and the three products by
numpy's own OpenBLAS with the arguments numpy's matmul passes (_blas_numba.numpy_gemm, numpy_gemv). What goes away
is the Python around them: 12 numpy calls and two f2py calls per frame. Compiled on first use and cached on disk
(numba cache=True), as _ukf_numba.py.
"""

from __future__ import annotations

from typing import TypeAlias

import numpy as np
from numpy.typing import NDArray

from kinect_agent.numba_cache import cache_for, numba
from kinect_agent.processing import _blas_numba

AVAILABLE = numba is not None and _blas_numba.AVAILABLE and _blas_numba.NUMPY_BLAS
CACHE = AVAILABLE and cache_for(__file__)  # numba's on-disk cache, or none (kinect_agent.numba_cache)
Floats: TypeAlias = NDArray[np.float64]
OK, P_PRED_NOT_POSITIVE, POTRF_FAILED, POTRS_FAILED = 0, 1, 2, 3  # rts_random_walk's status


def _rts_random_walk(
    xs: Floats, Ps: Floats, Q: Floats, q_scale: Floats, scaled: bool, covariances: bool
) -> tuple[int, int, int]:  # pragma: no cover - compiled
    """Smooths xs (T, n) and Ps (T, n, n) in place, as ukf._rts_random_walk: noise q_scale[k] · Q of step k
    (scaled True) or Q; covariances False: the means only (Ps stay the filtered ones, all the gain needs).
    Returns (status, k, info): OK, or the failure, the step k it happened at and LAPACK's info (dpotrf's > 0:
    P_PRED_NOT_POSITIVE, < 0: POTRF_FAILED; dpotrs's != 0: POTRS_FAILED); xs, Ps smoothed after k."""
    T, n = xs.shape
    Qk = np.empty((n, n))
    P_pred = np.empty((n, n))
    M = np.empty((n, n))
    CM = np.empty((n, n))
    Pk = np.empty((n, n))
    F = np.empty((n, n))  # P_pred's Fortran copy, then its factor (dpotrf 'L')
    C = np.empty((n, n))  # the gain: dpotrs's right-hand side Pᵀ in Fortran order, i.e. P in C order; then C
    dx = np.empty(n)
    Cdx = np.empty(n)
    for k in range(T - 2, -1, -1):
        x = xs[k]
        P = Ps[k]
        if scaled:
            q = q_scale[k]
            for i in range(n):
                for j in range(n):
                    Qk[i, j] = q * Q[i, j]
            for i in range(n):
                for j in range(n):
                    P_pred[i, j] = P[i, j] + Qk[i, j]
        else:
            for i in range(n):
                for j in range(n):
                    P_pred[i, j] = P[i, j] + Q[i, j]
        for i in range(n):
            for j in range(n):
                F[j, i] = P_pred[i, j]
        info = _blas_numba.potrf_lower_f(F, n)
        if info > 0:
            return P_PRED_NOT_POSITIVE, k, info
        if info < 0:
            return POTRF_FAILED, k, info
        for i in range(n):
            for j in range(n):
                C[i, j] = P[i, j]
        info = _blas_numba.potrs_lower_f(F, n, C, n)
        if info != 0:
            return POTRS_FAILED, k, info
        for i in range(n):
            dx[i] = xs[k + 1, i] - x[i]
        _blas_numba.numpy_gemv(C, dx, Cdx)
        for i in range(n):
            x[i] = x[i] + Cdx[i]
        if not covariances:
            continue
        for i in range(n):
            for j in range(n):
                M[i, j] = Ps[k + 1, i, j] - P_pred[i, j]
        _blas_numba.numpy_gemm(C, M, False, CM)
        _blas_numba.numpy_gemm(CM, C, True, Pk)
        for i in range(n):
            for j in range(n):
                Pk[i, j] = P[i, j] + Pk[i, j]
        for i in range(n):
            for j in range(n):
                M[i, j] = Pk[i, j] + Pk[j, i]
        for i in range(n):
            for j in range(n):
                P[i, j] = 0.5 * M[i, j]
    return OK, -1, 0


if AVAILABLE:
    rts_random_walk = numba.njit(cache=CACHE, nogil=True, error_model="numpy")(_rts_random_walk)
else:  # pragma: no cover - callers check AVAILABLE first
    rts_random_walk = None  # type: ignore[assignment]
