"""Compiled text of Skeleton CSV rows (skeleton_csv._rows), used for long recordings when numba is installed; the
Python %-format stays the reference and does every row the kernel leaves.

A cell of d decimals is the correctly rounded d-decimal text of the value, what Python's "%.{d}f" gives: x = |v|·10^d
(one rounding) rounded to the nearest integer. Rounding is monotonic and halves are exact below 2^52, so x never
crosses the half the exact product is nearest to; only a tie (x on a half: Python rounds the exact value, half to
even) and values of 1e15 or more after scaling are left to Python, with their whole row (the test for a tie keeps a
margin of 1e-15·x). The sign is the value's sign bit ("%.5f" % -1e-7 is "-0.00000"). A cell of 0 decimals is a
state, one digit 0-9 (else left to Python); NaN is an empty cell. Compiled on first use and cached on disk (numba
cache=True), as kinect_agent/processing/_ukf_numba.py; the install's warm-up compiles it (kinect_agent.live.warmup).
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
Bytes: TypeAlias = NDArray[np.uint8]
Bools: TypeAlias = NDArray[np.bool_]
CELL_BYTES = 24  # the most bytes a cell the kernel writes takes, its comma or line end included
_POW10 = np.array([10.0**i for i in range(16)])


def _write_rows(table: Floats, decimals: Ints, pow10: Floats, out: Bytes, left: Bools) -> int:  # pragma: no cover
    """Writes the rows of table (N, C) as text lines (cells joined by ',', each line ending in '\\n') into out
    (at least N·C·CELL_BYTES bytes) and returns the bytes written; left (N,) is set True for each row to be written by
    Python instead (its text in out is then to be replaced). decimals (C,): per column, d > 0 decimals or 0 (a state
    digit). pow10: 10.0^0 .. 10.0^15."""
    N, C = table.shape
    pos = 0
    digits = np.empty(20, dtype=np.uint8)
    for r in range(N):
        left[r] = False
        for c in range(C):
            v = table[r, c]
            d = decimals[c]
            if v != v:  # NaN: an empty cell
                pass
            elif d == 0:
                if v >= 0.0 and v <= 9.0 and v == math.floor(v):
                    out[pos] = 48 + int(v)
                    pos += 1
                else:
                    left[r] = True
            else:
                x = abs(v) * pow10[d]
                if not x < 1e15:  # also infinities
                    left[r] = True
                else:
                    whole = math.floor(x)
                    frac = x - whole  # exact below 2^52
                    if abs(frac - 0.5) <= 1e-15 * x:
                        left[r] = True
                    n = int(whole) + (1 if frac > 0.5 else 0)
                    if math.copysign(1.0, v) < 0.0:
                        out[pos] = 45  # '-'
                        pos += 1
                    k = 0
                    while True:  # n's digits, least significant first: at least d + 1 (a whole digit)
                        digits[k] = 48 + n % 10
                        n //= 10
                        k += 1
                        if k > d and n == 0:
                            break
                    for i in range(k - 1, -1, -1):
                        out[pos] = digits[i]
                        pos += 1
                        if i == d:
                            out[pos] = 46  # '.' after the last whole digit
                            pos += 1
            out[pos] = 44 if c < C - 1 else 10  # ',' or '\n'
            pos += 1
    return pos


if AVAILABLE:
    _write_rows_c = numba.njit(cache=CACHE, nogil=True, error_model="numpy")(_write_rows)


def rows_text(table: Floats, decimals: Ints) -> tuple[list[str], Bools]:
    """Returns (lines (N,) each ending in '\\n', left (N,) bool): the text of table (N, C) as described in the module
    docstring, and the rows whose line is to be made by Python instead. Needs AVAILABLE."""
    table = np.ascontiguousarray(table, dtype=np.float64)
    N, C = table.shape
    out = np.empty(N * C * CELL_BYTES, dtype=np.uint8)
    left = np.empty(N, dtype=np.bool_)
    size = _write_rows_c(table, np.ascontiguousarray(decimals, dtype=np.int64), _POW10, out, left)
    return out[:size].tobytes().decode("ascii").splitlines(keepends=True), left


__all__ = ["AVAILABLE", "rows_text"]
