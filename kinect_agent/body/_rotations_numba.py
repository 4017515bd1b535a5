"""Compiled rotations.matrix_to_quat, used when numba is installed (the numpy version stays reference and fallback;
tests hold both to the same results bit for bit).

The kernel does numpy's floating-point operations in numpy's order: each sum of the expressions left to right as
written, argmax's first maximum (a NaN wins, as in numpy), the norm as the square root of ((0 + w²) + x²) + y²) + z²
(numpy's reduction over a contiguous axis of 4), a division by it and the sign as a product by ±1. No fastmath (no
fused multiply-add). Compiled on first use and cached on disk (numba cache=True), as _fk_numba.py.
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


def _matrix_to_quat(R: Floats, out: Floats) -> None:  # pragma: no cover - compiled
    """out[i] = rotations.matrix_to_quat(R[i]) for R (N, 3, 3), out (N, 4) wxyz."""
    cand = np.empty((4, 4))
    diag = np.empty(4)
    for i in range(R.shape[0]):
        m00, m01, m02 = R[i, 0, 0], R[i, 0, 1], R[i, 0, 2]
        m10, m11, m12 = R[i, 1, 0], R[i, 1, 1], R[i, 1, 2]
        m20, m21, m22 = R[i, 2, 0], R[i, 2, 1], R[i, 2, 2]
        cand[0, 0], cand[0, 1], cand[0, 2], cand[0, 3] = 1 + m00 + m11 + m22, m21 - m12, m02 - m20, m10 - m01
        cand[1, 0], cand[1, 1], cand[1, 2], cand[1, 3] = m21 - m12, 1 + m00 - m11 - m22, m01 + m10, m02 + m20
        cand[2, 0], cand[2, 1], cand[2, 2], cand[2, 3] = m02 - m20, m01 + m10, 1 - m00 + m11 - m22, m12 + m21
        cand[3, 0], cand[3, 1], cand[3, 2], cand[3, 3] = m10 - m01, m02 + m20, m12 + m21, 1 - m00 - m11 + m22
        diag[0], diag[1], diag[2], diag[3] = cand[0, 0], cand[1, 1], cand[2, 2], cand[3, 3]
        best = 0
        for c in range(1, 4):
            if math.isnan(diag[best]):
                break
            if math.isnan(diag[c]) or diag[c] > diag[best]:
                best = c
        w, x, y, z = cand[best, 0], cand[best, 1], cand[best, 2], cand[best, 3]
        norm = math.sqrt((((0.0 + w * w) + x * x) + y * y) + z * z)
        w, x, y, z = w / norm, x / norm, y / norm, z / norm
        sign = -1.0 if w < 0 else 1.0
        out[i, 0], out[i, 1], out[i, 2], out[i, 3] = w * sign, x * sign, y * sign, z * sign


if AVAILABLE:
    matrix_to_quat = numba.njit(cache=CACHE, fastmath=False, nogil=True, error_model="numpy")(_matrix_to_quat)
else:  # pragma: no cover - callers check AVAILABLE first
    matrix_to_quat = None  # type: ignore[assignment]
