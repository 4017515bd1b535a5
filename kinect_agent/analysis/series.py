"""Conditioning of one angle series before it is measured: gap filling, spike removal, smoothing.

A series x: (T,) float, degrees, NaN where untracked, sampled at times t: (T,) s (strictly increasing, nearly
uniform; kernel widths use the median frame interval). Steps, in order:
    1. gaps (NaN) are filled by linear interpolation in time (edges hold the nearest value);
    2. a running median over median_s seconds removes spikes shorter than half that window;
    3. a Gaussian of SD smooth_s seconds removes jitter (zero phase, so peaks stay in place).
Angles are not unwrapped: each comes in its domain (kinect_agent.body.angles.DOMAIN_DEG), whose seam lies
where no limb goes, and every step above keeps a series inside the interval its samples span. Unwrapping turned a
mistracked jump across a seam into whole extra turns (a UI-PRMD sit-to-stand's shoulder flexion read 1319°).
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter1d, median_filter

MEDIAN_S = 0.2  # running-median window, s
SMOOTH_S = 0.1  # Gaussian SD, s
TRUNCATE = 3.0  # the Gaussian kernel spans ±3 SD


def frame_interval(t: np.ndarray) -> float:
    """Returns the median frame interval of t: (T,) s, in seconds (1/30 when T < 2)."""
    if t.shape[0] < 2:
        return 1.0 / 30.0
    return float(np.median(np.diff(t)))


def fill_gaps(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Returns x: (T,) with NaN replaced by linear interpolation over t: (T,) s; all-NaN input stays NaN."""
    finite = np.isfinite(x)
    if finite.all() or not finite.any():
        return x.astype(np.float64, copy=True)
    return np.interp(t, t[finite], x[finite])


def smooth(t: np.ndarray, x: np.ndarray, *, median_s: float = MEDIAN_S, smooth_s: float = SMOOTH_S) -> np.ndarray:
    """Returns the conditioned series (steps 1-3 above) of x: (T,) degrees at times t: (T,) s; NaN if x is all NaN.

    Series that are not angles (heights in metres) are conditioned alike.
    Raises ValueError when t and x differ in shape.
    """
    t = np.asarray(t, dtype=np.float64)
    x = np.asarray(x, dtype=np.float64)
    if t.ndim != 1 or x.shape != t.shape:
        raise ValueError(f"t and x must both have shape (T,), got {t.shape} and {x.shape}")
    y = fill_gaps(t, x)
    if y.shape[0] < 3 or not np.all(np.isfinite(y)):
        return y
    dt = frame_interval(t)
    size = max(1, int(round(median_s / dt)) | 1)
    if size > 1:
        y = median_filter(y, size=size, mode="nearest")
    sigma = smooth_s / dt
    if sigma > 0.3:
        y = gaussian_filter1d(y, sigma, mode="nearest", truncate=TRUNCATE)
    return y


def smooth_positions(t: np.ndarray, positions: np.ndarray, *, smooth_s: float = SMOOTH_S) -> np.ndarray:
    """Returns positions: (T, J, 3) metres with gaps filled per joint and axis and a Gaussian of SD smooth_s (s).

    Joints never tracked stay NaN. Raises ValueError on a shape other than (T, J, 3) with T = len(t).
    """
    t = np.asarray(t, dtype=np.float64)
    p = np.asarray(positions, dtype=np.float64)
    if p.ndim != 3 or p.shape[0] != t.shape[0] or p.shape[2] != 3:
        raise ValueError(f"positions must have shape ({t.shape[0]}, J, 3), got {p.shape}")
    flat = p.reshape(p.shape[0], -1).copy()
    gaps = ~np.isfinite(flat)
    for k in np.flatnonzero(gaps.any(axis=0)):
        flat[:, k] = fill_gaps(t, flat[:, k])
    sigma = smooth_s / frame_interval(t)
    if sigma > 0.3 and p.shape[0] > 2:
        ok = np.isfinite(flat).all(axis=0)
        if ok.all():  # the usual case (filtered positions): no column copies; columns are filtered independently
            flat = gaussian_filter1d(flat, sigma, axis=0, mode="nearest", truncate=TRUNCATE)
        else:
            flat[:, ok] = gaussian_filter1d(flat[:, ok], sigma, axis=0, mode="nearest", truncate=TRUNCATE)
    return flat.reshape(p.shape)


def dot3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Returns the dot products over the last axis (length 3) of a and b, (...,); faster than np.sum(a * b, -1)."""
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def norm3(v: np.ndarray) -> np.ndarray:
    """Returns the Euclidean norms over the last axis (length 3) of v, (...,)."""
    return np.sqrt(dot3(v, v))


def smooth_columns(
    t: np.ndarray, x: np.ndarray, *, median_s: float = MEDIAN_S, smooth_s: float = SMOOTH_S
) -> np.ndarray:
    """Returns smooth() applied to every column of x: (T, K) at times t: (T,) s, in one pass per step.

    median_s=0 skips the running median, smooth_s=0 the Gaussian. Columns with no finite value stay NaN.
    """
    t = np.asarray(t, dtype=np.float64)
    y = np.array(x, dtype=np.float64)
    if y.ndim != 2 or y.shape[0] != t.shape[0]:
        raise ValueError(f"x must have shape ({t.shape[0]}, K), got {y.shape}")
    for k in np.flatnonzero(~np.isfinite(y).all(axis=0)):
        y[:, k] = fill_gaps(t, y[:, k])
    ok = np.isfinite(y).all(axis=0)
    if y.shape[0] < 3 or not ok.any():
        return y
    z = y[:, ok]
    dt = frame_interval(t)
    size = max(1, int(round(median_s / dt)) | 1) if median_s > 0 else 1
    if size > 1:
        z = median_filter(z, size=(size, 1), mode="nearest")
    sigma = smooth_s / dt
    if sigma > 0.3:
        z = gaussian_filter1d(z, sigma, axis=0, mode="nearest", truncate=TRUNCATE)
    y[:, ok] = z
    return y
