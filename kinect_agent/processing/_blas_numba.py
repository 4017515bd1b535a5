"""LAPACK/BLAS routines (SciPy's, through scipy.linalg.cython_lapack/cython_blas) callable from numba kernels.

Each routine is bound by symbol name (llvmlite add_symbol + numba ExternalFunction), so kernels that call it can
still be cached on disk. The wrappers take C-ordered float64 arrays; Fortran sees each array transposed, so
comments name both views. Used by the fused UKF step (_ukf_numba.py) and the RTS loop (_rts_numba.py). Only defined
when numba is installed.

numpy_gemm / numpy_gemv call numpy's own OpenBLAS (its CBLAS, 64-bit integers) with the arguments numpy's matmul
passes for C-ordered float64 operands, so a kernel's product has the bits of numpy's `@` (SciPy's OpenBLAS is
another build: its dgemm is not guaranteed to give them). NUMPY_BLAS is False when that library is not found (numpy
built against another BLAS); callers then keep numpy.
"""

from __future__ import annotations

import ctypes
from pathlib import Path
from typing import Protocol, TypeAlias, cast

import numpy as np
from numpy.typing import NDArray

from kinect_agent.numba_cache import cache_for

try:
    import numba
    from llvmlite import binding as _llvm
    from numba import types as _t
    from numba.extending import get_cython_function_address as _address
except ImportError:  # pragma: no cover - exercised only where numba is absent
    numba = None  # type: ignore[assignment]

AVAILABLE = numba is not None
CACHE = AVAILABLE and cache_for(__file__)  # numba's on-disk cache, or none (kinect_agent.numba_cache)
Floats: TypeAlias = NDArray[np.float64]


class _Pointer(Protocol):
    """What a kernel passes for a Fortran or C pointer argument: an array's `.ctypes` (ctypes' `_as_parameter_`)."""

    @property
    def _as_parameter_(self) -> ctypes.c_void_p: ...


# The external routines as kernels call them (numba types ExternalFunction calls by the signatures given below; these
# protocols give mypy the same argument lists). Fortran passes every argument by pointer.
class _Dpotrf(Protocol):
    def __call__(self, uplo: _Pointer, n: _Pointer, a: _Pointer, lda: _Pointer, info: _Pointer, /) -> None: ...


class _Dpotrs(Protocol):
    def __call__(
        self, uplo: _Pointer, n: _Pointer, nrhs: _Pointer, a: _Pointer, lda: _Pointer, b: _Pointer, ldb: _Pointer,
        info: _Pointer, /,
    ) -> None: ...  # fmt: skip


class _Dtrsm(Protocol):
    def __call__(
        self, side: _Pointer, uplo: _Pointer, transa: _Pointer, diag: _Pointer, m: _Pointer, n: _Pointer,
        alpha: _Pointer, a: _Pointer, lda: _Pointer, b: _Pointer, ldb: _Pointer, /,
    ) -> None: ...  # fmt: skip


class _Dsyrk(Protocol):
    def __call__(
        self, uplo: _Pointer, trans: _Pointer, n: _Pointer, k: _Pointer, alpha: _Pointer, a: _Pointer, lda: _Pointer,
        beta: _Pointer, c: _Pointer, ldc: _Pointer, /,
    ) -> None: ...  # fmt: skip


class _CblasDgemm(Protocol):
    def __call__(
        self, order: int, transa: int, transb: int, m: int, n: int, k: int, alpha: float, a: _Pointer, lda: int,
        b: _Pointer, ldb: int, beta: float, c: _Pointer, ldc: int, /,
    ) -> None: ...  # fmt: skip


class _CblasDgemv(Protocol):
    def __call__(
        self, order: int, trans: int, m: int, n: int, alpha: float, a: _Pointer, lda: int, x: _Pointer, incx: int,
        beta: float, y: _Pointer, incy: int, /,
    ) -> None: ...  # fmt: skip


if AVAILABLE:
    _llvm.add_symbol("kinect_dpotrf", _address("scipy.linalg.cython_lapack", "dpotrf"))
    _llvm.add_symbol("kinect_dtrsm", _address("scipy.linalg.cython_blas", "dtrsm"))
    _llvm.add_symbol("kinect_dsyrk", _address("scipy.linalg.cython_blas", "dsyrk"))
    _vp = _t.voidptr
    # numba's ExternalFunction is a numba type, callable only inside a kernel: each is cast once to its protocol.
    _dpotrf = cast(_Dpotrf, _t.ExternalFunction("kinect_dpotrf", _t.void(_vp, _vp, _vp, _vp, _vp)))
    _dtrsm = cast(_Dtrsm, _t.ExternalFunction("kinect_dtrsm", _t.void(*([_vp] * 11))))
    _dsyrk = cast(_Dsyrk, _t.ExternalFunction("kinect_dsyrk", _t.void(*([_vp] * 10))))
    _llvm.add_symbol("kinect_dpotrs", _address("scipy.linalg.cython_lapack", "dpotrs"))
    _dpotrs = cast(_Dpotrs, _t.ExternalFunction("kinect_dpotrs", _t.void(*([_vp] * 8))))


def _numpy_cblas() -> tuple[int, int] | None:
    """Returns the addresses of (cblas_dgemm, cblas_dgemv) in the OpenBLAS that numpy's matmul calls (the wheel's
    numpy.libs/libscipy_openblas64_*.so, symbols scipy_cblas_*64_), or None when numpy has no such library."""
    libs = Path(np.__file__).resolve().parent.parent / "numpy.libs"
    for path in sorted(libs.glob("libscipy_openblas64_*.so")):
        lib = ctypes.CDLL(str(path))  # already loaded by numpy: the same handle, the same code
        try:
            gemm, gemv = lib.scipy_cblas_dgemm64_, lib.scipy_cblas_dgemv64_
        except AttributeError:
            continue
        return ctypes.cast(gemm, ctypes.c_void_p).value or 0, ctypes.cast(gemv, ctypes.c_void_p).value or 0
    return None


_NUMPY_CBLAS = _numpy_cblas() if AVAILABLE else None
NUMPY_BLAS = _NUMPY_CBLAS is not None and all(_NUMPY_CBLAS)
ROW_MAJOR, COL_MAJOR, NO_TRANS, TRANS = 101, 102, 111, 112  # CBLAS enums
if NUMPY_BLAS:
    _llvm.add_symbol("kinect_numpy_dgemm", _NUMPY_CBLAS[0])  # type: ignore[index]
    _llvm.add_symbol("kinect_numpy_dgemv", _NUMPY_CBLAS[1])  # type: ignore[index]
    _i32, _i64, _f64 = _t.int32, _t.int64, _t.float64
    _ngemm = cast(_CblasDgemm, _t.ExternalFunction("kinect_numpy_dgemm", _t.void(
        _i32, _i32, _i32, _i64, _i64, _i64, _f64, _vp, _i64, _vp, _i64, _f64, _vp, _i64)))  # fmt: skip
    _ngemv = cast(_CblasDgemv, _t.ExternalFunction("kinect_numpy_dgemv", _t.void(
        _i32, _i32, _i64, _i64, _f64, _vp, _i64, _vp, _i64, _f64, _vp, _i64)))  # fmt: skip

    @numba.njit(cache=CACHE, nogil=True)
    def numpy_gemm(A: Floats, B: Floats, transpose_b: bool, out: Floats) -> None:  # pragma: no cover - compiled
        """out ← A @ B (transpose_b False) or A @ Bᵀ (True), all (n, n) C order: numpy's matmul for C-ordered A and
        B (B.T: an F-ordered view), i.e. cblas_dgemm(RowMajor, NoTrans, NoTrans|Trans, n, n, n, 1, A, n, B, n, 0,
        out, n)."""
        n = A.shape[0]
        _ngemm(ROW_MAJOR, NO_TRANS, TRANS if transpose_b else NO_TRANS, n, n, n, 1.0, A.ctypes, n, B.ctypes, n, 0.0,
               out.ctypes, n)  # fmt: skip

    @numba.njit(cache=CACHE, nogil=True)
    def numpy_gemv(A: Floats, v: Floats, out: Floats) -> None:  # pragma: no cover - compiled
        """out ← A @ v for A (m, n) C order, v (n,), out (m,) contiguous: numpy's matmul of a matrix and a vector,
        cblas_dgemv(ColMajor, Trans, n, m, 1, A, n, v, 1, 0, out, 1)."""
        m, n = A.shape
        _ngemv(COL_MAJOR, TRANS, n, m, 1.0, A.ctypes, n, v.ctypes, 1, 0.0, out.ctypes, 1)

else:  # pragma: no cover - numpy without its OpenBLAS wheel library
    numpy_gemm = numpy_gemv = None  # type: ignore[assignment]

if AVAILABLE:

    @numba.njit(cache=CACHE, nogil=True)
    def cholesky_lower(A: Floats, n: int) -> int:  # pragma: no cover - compiled
        """Overwrites the lower triangle of A[:n, :n] (C order, leading dimension A.shape[1]) with L, L Lᵀ = A.

        The strict upper triangle is left as it was. Returns LAPACK's info: 0 = done, > 0 = not positive definite.
        (Fortran: dpotrf 'U' on Aᵀ = A.)
        """
        chars = np.array([85], dtype=np.uint8)  # 'U'
        ints = np.array([n, A.shape[1], 0], dtype=np.int32)
        _dpotrf(chars.ctypes, ints[0:].ctypes, A.ctypes, ints[1:].ctypes, ints[2:].ctypes)
        return ints[2]

    @numba.njit(cache=CACHE, nogil=True)
    def solve_lower(Lm: Floats, k: int, B: Floats, rows: int, cols: int) -> None:  # pragma: no cover - compiled
        """Overwrites B[:rows, :cols] (C order) with L⁻¹ B, L = lower triangle of Lm[:k, :k], k = rows.

        (Fortran: Bᵀ ← Bᵀ U⁻¹ with U = Lᵀ the upper triangle of Lmᵀ: dtrsm 'R', 'U', 'N', 'N'.)
        """
        chars = np.array([82, 85, 78, 78], dtype=np.uint8)  # 'R' 'U' 'N' 'N'
        ints = np.array([cols, rows, Lm.shape[1], B.shape[1]], dtype=np.int32)
        one = np.ones(1)
        _dtrsm(chars[0:].ctypes, chars[1:].ctypes, chars[2:].ctypes, chars[3:].ctypes, ints[0:].ctypes,
               ints[1:].ctypes, one.ctypes, Lm.ctypes, ints[2:].ctypes, B.ctypes, ints[3:].ctypes)  # fmt: skip

    @numba.njit(cache=CACHE, nogil=True)
    def gram_lower(
        A: Floats, rows: int, cols: int, alpha: float, beta: float, C: Floats
    ) -> None:  # pragma: no cover - compiled
        """C ← alpha · Aᵀ A + beta · C on the lower triangle of C[:cols, :cols]; A is A[:rows, :cols] (C order).

        (Fortran: Aᵀ is cols × rows, dsyrk 'U', 'N' on Cᵀ.)
        """
        chars = np.array([85, 78], dtype=np.uint8)  # 'U' 'N'
        ints = np.array([cols, rows, A.shape[1], C.shape[1]], dtype=np.int32)
        ab = np.array([alpha, beta])
        _dsyrk(chars[0:].ctypes, chars[1:].ctypes, ints[0:].ctypes, ints[1:].ctypes, ab[0:].ctypes, A.ctypes,
               ints[2:].ctypes, ab[1:].ctypes, C.ctypes, ints[3:].ctypes)  # fmt: skip

    @numba.njit(cache=CACHE, nogil=True)
    def gram_rows_lower(
        A: Floats, rows: int, cols: int, lda: int, alpha: float, C: Floats
    ) -> None:  # pragma: no cover - compiled
        """C ← alpha · A Aᵀ on the lower triangle of C[:rows, :rows]; A is rows × cols in C order with leading
        dimension lda, starting at A[0] (a flat view, so it may start inside a larger array).

        (Fortran: Aᵀ is cols × rows, dsyrk 'U', 'T' on Cᵀ.)
        """
        chars = np.array([85, 84], dtype=np.uint8)  # 'U' 'T'
        ints = np.array([rows, cols, lda, C.shape[1]], dtype=np.int32)
        ab = np.array([alpha, 0.0])
        _dsyrk(chars[0:].ctypes, chars[1:].ctypes, ints[0:].ctypes, ints[1:].ctypes, ab[0:].ctypes, A.ctypes,
               ints[2:].ctypes, ab[1:].ctypes, C.ctypes, ints[3:].ctypes)  # fmt: skip

    @numba.njit(cache=CACHE, nogil=True)
    def potrf_lower_f(A: Floats, n: int) -> int:  # pragma: no cover - compiled
        """dpotrf 'L' on A[:n, :n] read as a Fortran array (leading dimension A.shape[1]): what SciPy's
        lapack.dpotrf(a, lower=1, clean=0) does with a Fortran copy of a, given Aᵀ's C-order buffer. Returns info."""
        chars = np.array([76], dtype=np.uint8)  # 'L'
        ints = np.array([n, A.shape[1], 0], dtype=np.int32)
        _dpotrf(chars.ctypes, ints[0:].ctypes, A.ctypes, ints[1:].ctypes, ints[2:].ctypes)
        return ints[2]

    @numba.njit(cache=CACHE, nogil=True)
    def potrs_lower_f(Lf: Floats, n: int, B: Floats, nrhs: int) -> int:  # pragma: no cover - compiled
        """dpotrs 'L' with the factor of potrf_lower_f and B[:nrhs, :n] read as a Fortran (n, nrhs) array: SciPy's
        lapack.dpotrs(c, b, lower=1) with b's Fortran copy held in B (C order: B = bᵀ). Returns info."""
        chars = np.array([76], dtype=np.uint8)  # 'L'
        ints = np.array([n, nrhs, Lf.shape[1], B.shape[1], 0], dtype=np.int32)
        _dpotrs(chars.ctypes, ints[0:].ctypes, ints[1:].ctypes, Lf.ctypes, ints[2:].ctypes, B.ctypes,
                ints[3:].ctypes, ints[4:].ctypes)  # fmt: skip
        return ints[4]

else:  # pragma: no cover - callers check AVAILABLE first
    potrf_lower_f = potrs_lower_f = None  # type: ignore[assignment]
    cholesky_lower = solve_lower = gram_lower = gram_rows_lower = None  # type: ignore[assignment]
