"""Compiled kernel of the simulated Kinect noise (kinect_noise.refine_offsets' sweeps), used when numba is installed;
numpy stays reference and fallback, and tests hold both to the same offsets bit for bit.

The kernel does the same floating-point operations in the same order as the numpy expressions it replaces (numpy's
einsum sums an index of 3 as (x0² + x2²) + x1²), without the temporaries: no fused multiply-add, no reassociation
(no fastmath).
Compiled on first use and cached on disk (numba cache=True), as kinect_agent/processing/_outliers_numba.py.
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


def _refine_sweeps(
    truth: Floats, m: Floats, radius: Floats, wanted_by_bone: Floats, parents: Ints, children: Ints, gain: Floats,
    sweeps: int
) -> None:  # pragma: no cover - compiled  # fmt: skip
    """kinect_noise.refine_offsets' sweeps in place on m (J, T, 3) m: truth (J, T, 3) m, radius (J, T) m, wanted_by_bone
    (19, T) m, parents and children (19,) int, gain (19,) float; sweeps: how many."""
    J, T = radius.shape
    for _ in range(sweeps):
        for k in range(parents.shape[0]):
            p, c, g = parents[k], children[k], gain[k]
            for t in range(T):
                v0 = m[c, t, 0] - m[p, t, 0]
                v1 = m[c, t, 1] - m[p, t, 1]
                v2 = m[c, t, 2] - m[p, t, 2]
                n = max(math.sqrt((v0 * v0 + v2 * v2) + v1 * v1), 1e-12)
                s = g * (n - wanted_by_bone[k, t]) / n
                c0, c1, c2 = v0 * s, v1 * s, v2 * s
                m[p, t, 0] += c0
                m[p, t, 1] += c1
                m[p, t, 2] += c2
                m[c, t, 0] -= c0
                m[c, t, 1] -= c1
                m[c, t, 2] -= c2
        for j in range(J):
            for t in range(T):
                r0 = m[j, t, 0] - truth[j, t, 0]
                r1 = m[j, t, 1] - truth[j, t, 1]
                r2 = m[j, t, 2] - truth[j, t, 2]
                f = radius[j, t] / max(math.sqrt((r0 * r0 + r2 * r2) + r1 * r1), 1e-12)
                m[j, t, 0] = truth[j, t, 0] + r0 * f
                m[j, t, 1] = truth[j, t, 1] + r1 * f
                m[j, t, 2] = truth[j, t, 2] + r2 * f


if AVAILABLE:
    refine_sweeps = numba.njit(cache=CACHE, nogil=True, error_model="numpy")(_refine_sweeps)
