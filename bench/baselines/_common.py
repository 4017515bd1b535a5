"""Input checks and gap handling shared by the baselines."""

from __future__ import annotations

import numpy as np


def check_input(t: np.ndarray, positions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Returns (t (T,) float64 s, positions (T, C) float64 m flattened per channel); raises ValueError on bad shapes.

    positions: (T, ...) m, NaN = missing; every trailing axis is flattened into channels C.
    """
    t = np.asarray(t, dtype=np.float64)
    positions = np.asarray(positions, dtype=np.float64)
    if t.ndim != 1:
        raise ValueError(f"t must have shape (T,), got {t.shape}")
    if positions.ndim < 1 or positions.shape[0] != t.shape[0]:
        raise ValueError(f"positions must have shape (T, ...) with T = {t.shape[0]}, got {positions.shape}")
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise ValueError("t must be finite and strictly increasing (seconds)")
    return t, positions.reshape(t.shape[0], -1)


def sample_rate(t: np.ndarray) -> float:
    """Returns the rate, Hz, of the median frame interval of t (T,) s (30 Hz for a single frame)."""
    return float(1.0 / np.median(np.diff(t))) if t.shape[0] > 1 else 30.0


def fill_gaps(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Returns x (T, C) with NaN runs filled by linear interpolation in time, ends held at the nearest sample.

    A channel without any sample stays NaN.
    """
    out = x.copy()
    for c in np.flatnonzero(~np.all(np.isfinite(x), axis=0)):
        ok = np.isfinite(x[:, c])
        if ok.any():
            out[:, c] = np.interp(t, t[ok], x[ok, c])
    return out


def hold_last(x: np.ndarray) -> np.ndarray:
    """Returns x (T, ...) with every NaN replaced by the last finite value before it (leading NaN: next value).

    This is what a live display does with a frame it did not get: it keeps showing the previous pose.
    """
    flat = x.reshape(x.shape[0], -1)
    ok = np.isfinite(flat)
    idx = np.where(ok, np.arange(flat.shape[0])[:, None], 0)
    np.maximum.accumulate(idx, axis=0, out=idx)
    out = np.take_along_axis(flat, idx, axis=0)
    first = np.argmax(ok, axis=0)  # leading gaps: the first sample
    lead = ~np.isfinite(out)
    out = np.where(lead, flat[first, np.arange(flat.shape[1])], out)
    return out.reshape(x.shape)
