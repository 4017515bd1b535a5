"""Range of motion of every clinical joint angle over a session.

Definition. For each angle of kinect_agent.body.angles.ANGLE_NAMES, computed from smoothed positions
(series.smooth_positions: gaps filled, Gaussian of SD 0.1 s; report.py passes those angles with presmoothed=True)
or else smoothed here (Gaussian of SD 0.1 s), and unwrapped (period 360°), then
    min_deg = 1st percentile, max_deg = 99th percentile, range_deg = max_deg − min_deg   (degrees)
The percentiles ignore the last residual glitches (under 1 % of the frames at either end); the smoothing costs
under a degree at the turning points of ordinary exercise movements. An angle with no finite value reads None.
"""

from __future__ import annotations

import numpy as np

from kinect_agent.analysis import series

LOW_PCT, HIGH_PCT = 1.0, 99.0


def angle_rom(t: np.ndarray, x: np.ndarray) -> dict[str, float | None]:
    """Returns {"min_deg", "max_deg", "range_deg"} of one angle x: (T,) degrees at times t: (T,) s."""
    y = series.smooth(t, x)
    finite = y[np.isfinite(y)]
    if finite.size == 0:
        return {"min_deg": None, "max_deg": None, "range_deg": None}
    lo, hi = np.percentile(finite, [LOW_PCT, HIGH_PCT])
    return {"min_deg": round(float(lo), 1), "max_deg": round(float(hi), 1), "range_deg": round(float(hi - lo), 1)}


def range_of_motion(
    t: np.ndarray, angles: dict[str, np.ndarray], *, presmoothed: bool = False
) -> dict[str, dict[str, float | None]]:
    """Returns {angle: {"min_deg", "max_deg", "range_deg"}} for angles {name: (T,) degrees} at times t: (T,) s.

    presmoothed: the angles come from smoothed positions, so only gaps are filled and angles unwrapped.
    """
    t = np.asarray(t, dtype=np.float64)
    names = list(angles)
    if not names:
        return {}
    stacked = np.stack([np.asarray(angles[n], dtype=np.float64) for n in names], axis=1)
    y = series.smooth_columns(t, stacked, median_s=0.0, smooth_s=0.0 if presmoothed else series.SMOOTH_S)
    ok = np.isfinite(y).all(axis=0) & (y.shape[0] > 0)
    out: dict[str, dict[str, float | None]] = {n: {"min_deg": None, "max_deg": None, "range_deg": None} for n in names}
    if ok.any():
        lo, hi = np.percentile(y[:, ok], [LOW_PCT, HIGH_PCT], axis=0)
        for k, name in enumerate(np.array(names)[ok]):
            out[str(name)] = {
                "min_deg": round(float(lo[k]), 1),
                "max_deg": round(float(hi[k]), 1),
                "range_deg": round(float(hi[k] - lo[k]), 1),
            }
    return out
