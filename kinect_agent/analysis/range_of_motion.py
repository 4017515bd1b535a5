"""Range of motion of every clinical joint angle over a session.

Definition. For each angle of kinect_agent.body.angles.ANGLE_NAMES, computed from smoothed positions
(series.smooth_positions: gaps filled, Gaussian of SD 0.1 s; report.py passes those angles with presmoothed=True)
or else smoothed here (series.smooth_columns: gaps filled, running median, Gaussian of SD 0.1 s), over the frames
where the angle is defined (finite before smoothing: a planar angle is undefined while its limb is out of its
plane, angles.DOMAIN_DEG):
    min_deg = 1st percentile, max_deg = 99th percentile, range_deg = max_deg − min_deg   (degrees)
The percentiles ignore the last residual glitches (under 1 % of the frames at either end); the smoothing costs
under a degree at the turning points of ordinary exercise movements. Angles are never unwrapped, so min_deg and
max_deg lie in the angle's domain. An angle with no defined frame reads None.
"""

from __future__ import annotations

import numpy as np

from kinect_agent.analysis import series

LOW_PCT, HIGH_PCT = 1.0, 99.0
_NONE: dict[str, float | None] = {"min_deg": None, "max_deg": None, "range_deg": None}


def _rom(values: np.ndarray) -> dict[str, float | None]:
    """Returns the three numbers of one angle from its defined values (K,) degrees."""
    if values.size == 0:
        return dict(_NONE)
    lo, hi = np.percentile(values, [LOW_PCT, HIGH_PCT])
    return {"min_deg": round(float(lo), 1), "max_deg": round(float(hi), 1), "range_deg": round(float(hi - lo), 1)}


def angle_rom(t: np.ndarray, x: np.ndarray) -> dict[str, float | None]:
    """Returns {"min_deg", "max_deg", "range_deg"} of one angle x: (T,) degrees at times t: (T,) s."""
    x = np.asarray(x, dtype=np.float64)
    y = series.smooth(t, x)
    return _rom(y[np.isfinite(x) & np.isfinite(y)])


def range_of_motion(
    t: np.ndarray, angles: dict[str, np.ndarray], *, presmoothed: bool = False
) -> dict[str, dict[str, float | None]]:
    """Returns {angle: {"min_deg", "max_deg", "range_deg"}} for angles {name: (T,) degrees} at times t: (T,) s.

    presmoothed: the angles come from smoothed positions and are measured as they are.
    """
    t = np.asarray(t, dtype=np.float64)
    names = list(angles)
    if not names:
        return {}
    stacked = np.stack([np.asarray(angles[n], dtype=np.float64) for n in names], axis=1)
    y = stacked if presmoothed else series.smooth_columns(t, stacked)
    defined = np.isfinite(stacked) & np.isfinite(y)
    return {name: _rom(y[defined[:, k], k]) for k, name in enumerate(names)}
