"""The Kinect SDK's joint smoothing: Holt double-exponential smoothing with jitter removal and bounded prediction.

Reference: M. Azimi, "Skeletal Joint Smoothing White Paper", Microsoft (Kinect for Windows SDK 1.x), and the
SDK's TRANSFORM_SMOOTH_PARAMETERS / FilterDoubleExponential sample (KinectJointFilter.cpp). Per joint and frame,
with raw position x_n, previous filtered position L, trend b:

    frame 1 of a run:  L = x_n, b = 0
    frame 2:           L = (x_n + x_{n−1}) / 2, b = c·(L − L_prev) + (1 − c)·b_prev
    later:             jitter: d = |x_n − L_prev|; J = x_n·d/r + L_prev·(1 − d/r) if d ≤ r, else x_n
                       L = (1 − s)·J + s·(L_prev + b_prev);  b = c·(L − L_prev) + (1 − c)·b_prev
    output:            P = L + p·b; if |P − x_n| > m: P = P·m/|P − x_n| + x_n·(1 − m/|P − x_n|)

s smoothing, c correction, p prediction (frames), r jitter radius (m), m max deviation radius (m). Inferred joints
(state 1) use 2r and 2m, as the SDK sample does. An untracked frame (NaN) resets the joint's filter and gives NaN
(the SDK resets too; it also stores the zero vector as the "previous raw" position, an artefact left out here).
The steady state on a ramp of v m/frame below the jitter radius lags by e = √(v·r) − v (filtered) and the output
by e − p·v; above it the jitter stage passes x_n and the output leads by p·v (tests/bench/test_holt.py).
"""

from __future__ import annotations

import numpy as np

from bench.baselines._common import check_input

SMOOTHING = 0.25
CORRECTION = 0.25
PREDICTION = 0.25
JITTER_RADIUS_M = 0.03
MAX_DEVIATION_RADIUS_M = 0.05
INFERRED = 1


def holt_kinect(
    t: np.ndarray,
    positions: np.ndarray,
    state: np.ndarray | None = None,
    *,
    smoothing: float = SMOOTHING,
    correction: float = CORRECTION,
    prediction: float = PREDICTION,
    jitter_radius: float = JITTER_RADIUS_M,
    max_deviation_radius: float = MAX_DEVIATION_RADIUS_M,
) -> np.ndarray:
    """Returns the SDK-smoothed positions (T, J, 3) m, NaN where the input is NaN.

    t: (T,) s (the SDK works per frame; t only fixes T). positions: (T, J, 3) m, NaN = untracked.
    state: (T, J) 0/1/2 or None (all tracked); inferred joints get twice the radii.
    """
    t, _ = check_input(t, positions)
    x = np.asarray(positions, dtype=np.float64)
    if x.ndim != 3 or x.shape[2] != 3:
        raise ValueError(f"positions must have shape (T, J, 3), got {x.shape}")
    T, J, _ = x.shape
    if state is not None and np.shape(state) != (T, J):
        raise ValueError(f"state must have shape {(T, J)}, got {np.shape(state)}")
    for name, v in (("smoothing", smoothing), ("correction", correction)):
        if not 0.0 <= v <= 1.0:
            raise ValueError(f"{name} must be in [0, 1], got {v!r}")
    if prediction < 0 or max_deviation_radius <= 0:
        raise ValueError("prediction must be >= 0 and max_deviation_radius > 0")
    r_base = max(jitter_radius, 1e-4)  # the SDK's guard against division by zero (0.1 mm)
    scale = np.ones((T, J)) if state is None else np.where(np.asarray(state) == INFERRED, 2.0, 1.0)
    out = np.full_like(x, np.nan)
    count = np.zeros(J, dtype=int)
    L = np.zeros((J, 3))
    b = np.zeros((J, 3))
    raw_prev = np.zeros((J, 3))
    for n in range(T):
        xn = x[n]
        valid = np.all(np.isfinite(xn), axis=1)
        count[~valid] = 0
        r, m = r_base * scale[n][:, None], max_deviation_radius * scale[n][:, None]
        first, second, later = valid & (count == 0), valid & (count == 1), valid & (count >= 2)
        L_new, b_new = L.copy(), b.copy()
        L_new[first], b_new[first] = xn[first], 0.0
        avg = 0.5 * (xn + raw_prev)
        L_new[second] = avg[second]
        b_new[second] = correction * (avg[second] - L[second]) + (1.0 - correction) * b[second]
        d = np.linalg.norm(xn - L, axis=1, keepdims=True)
        w = np.clip(d / r, 0.0, 1.0)  # d > r: the raw position itself
        jit = np.where(d <= r, xn * w + L * (1.0 - w), xn)
        smooth = (1.0 - smoothing) * jit + smoothing * (L + b)
        L_new[later] = smooth[later]
        b_new[later] = correction * (smooth[later] - L[later]) + (1.0 - correction) * b[later]
        pred = L_new + prediction * b_new
        dev = np.linalg.norm(pred - xn, axis=1, keepdims=True)
        f = np.where(dev > m, m / np.where(dev > 0, dev, 1.0), 1.0)
        pred = pred * f + xn * (1.0 - f)
        out[n, valid] = pred[valid]
        L[valid], b[valid], raw_prev[valid] = L_new[valid], b_new[valid], xn[valid]
        count[valid] += 1
    return out
