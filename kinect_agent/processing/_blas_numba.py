"""LAPACK/BLAS routines (SciPy's, through scipy.linalg.cython_lapack/cython_blas) callable from numba kernels.

Each routine is bound by symbol name (llvmlite add_symbol + numba ExternalFunction), so kernels that call it can
still be cached on disk. The wrappers take C-ordered float64 arrays; Fortran sees each array transposed, so
comments name both views. Used by the fused UKF step in _fk_numba.py. Only defined when numba is installed.
"""

from __future__ import annotations

import numpy as np

try:
    import numba
    from llvmlite import binding as _llvm
    from numba import types as _t
    from numba.extending import get_cython_function_address as _address
except ImportError:  # pragma: no cover - exercised only where numba is absent
    numba = None  # type: ignore[assignment]

AVAILABLE = numba is not None

if AVAILABLE:
    _llvm.add_symbol("kinect_dpotrf", _address("scipy.linalg.cython_lapack", "dpotrf"))
    _llvm.add_symbol("kinect_dtrsm", _address("scipy.linalg.cython_blas", "dtrsm"))
    _llvm.add_symbol("kinect_dsyrk", _address("scipy.linalg.cython_blas", "dsyrk"))
    _vp = _t.voidptr
    _dpotrf = _t.ExternalFunction("kinect_dpotrf", _t.void(_vp, _vp, _vp, _vp, _vp))
    _dtrsm = _t.ExternalFunction("kinect_dtrsm", _t.void(*([_vp] * 11)))
    _dsyrk = _t.ExternalFunction("kinect_dsyrk", _t.void(*([_vp] * 10)))

    @numba.njit(cache=True, nogil=True)
    def cholesky_lower(A, n):  # pragma: no cover - compiled
        """Overwrites the lower triangle of A[:n, :n] (C order, leading dimension A.shape[1]) with L, L Lᵀ = A.

        The strict upper triangle is left as it was. Returns LAPACK's info: 0 = done, > 0 = not positive definite.
        (Fortran: dpotrf 'U' on Aᵀ = A.)
        """
        chars = np.array([85], dtype=np.uint8)  # 'U'
        ints = np.array([n, A.shape[1], 0], dtype=np.int32)
        _dpotrf(chars.ctypes, ints[0:].ctypes, A.ctypes, ints[1:].ctypes, ints[2:].ctypes)
        return ints[2]

    @numba.njit(cache=True, nogil=True)
    def solve_lower(Lm, k, B, rows, cols):  # pragma: no cover - compiled
        """Overwrites B[:rows, :cols] (C order) with L⁻¹ B, L = lower triangle of Lm[:k, :k], k = rows.

        (Fortran: Bᵀ ← Bᵀ U⁻¹ with U = Lᵀ the upper triangle of Lmᵀ: dtrsm 'R', 'U', 'N', 'N'.)
        """
        chars = np.array([82, 85, 78, 78], dtype=np.uint8)  # 'R' 'U' 'N' 'N'
        ints = np.array([cols, rows, Lm.shape[1], B.shape[1]], dtype=np.int32)
        one = np.ones(1)
        _dtrsm(chars[0:].ctypes, chars[1:].ctypes, chars[2:].ctypes, chars[3:].ctypes, ints[0:].ctypes,
               ints[1:].ctypes, one.ctypes, Lm.ctypes, ints[2:].ctypes, B.ctypes, ints[3:].ctypes)  # fmt: skip

    @numba.njit(cache=True, nogil=True)
    def gram_lower(A, rows, cols, alpha, beta, C):  # pragma: no cover - compiled
        """C ← alpha · Aᵀ A + beta · C on the lower triangle of C[:cols, :cols]; A is A[:rows, :cols] (C order).

        (Fortran: Aᵀ is cols × rows, dsyrk 'U', 'N' on Cᵀ.)
        """
        chars = np.array([85, 78], dtype=np.uint8)  # 'U' 'N'
        ints = np.array([cols, rows, A.shape[1], C.shape[1]], dtype=np.int32)
        ab = np.array([alpha, beta])
        _dsyrk(chars[0:].ctypes, chars[1:].ctypes, ints[0:].ctypes, ints[1:].ctypes, ab[0:].ctypes, A.ctypes,
               ints[2:].ctypes, ab[1:].ctypes, C.ctypes, ints[3:].ctypes)  # fmt: skip

    @numba.njit(cache=True, nogil=True)
    def gram_rows_lower(A, rows, cols, lda, alpha, C):  # pragma: no cover - compiled
        """C ← alpha · A Aᵀ on the lower triangle of C[:rows, :rows]; A is rows × cols in C order with leading
        dimension lda, starting at A[0] (a flat view, so it may start inside a larger array).

        (Fortran: Aᵀ is cols × rows, dsyrk 'U', 'T' on Cᵀ.)
        """
        chars = np.array([85, 84], dtype=np.uint8)  # 'U' 'T'
        ints = np.array([rows, cols, lda, C.shape[1]], dtype=np.int32)
        ab = np.array([alpha, 0.0])
        _dsyrk(chars[0:].ctypes, chars[1:].ctypes, ints[0:].ctypes, ints[1:].ctypes, ab[0:].ctypes, A.ctypes,
               ints[2:].ctypes, ab[1:].ctypes, C.ctypes, ints[3:].ctypes)  # fmt: skip

else:  # pragma: no cover - callers check AVAILABLE first
    cholesky_lower = solve_lower = gram_lower = gram_rows_lower = None  # type: ignore[assignment]
