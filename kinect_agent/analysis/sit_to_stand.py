"""Sit-to-stand transitions: how long the patient takes to rise, from the height of the hips.

Definitions:
    hip height h(t)  = y of ROOT (hip centre), metres, camera frame (y up), smoothed (series.smooth, 0.2 s running
                       median then Gaussian SD 0.1 s);
    seated / standing levels = the 5th / 95th percentile of h; their difference D must be at least MIN_RISE_M
                       (0.15 m; sitting down lowers the hips of an adult by 0.3-0.5 m), otherwise None;
    a transition     = h rising from below seated + LOW_FRAC·D (20 %) to above seated + HIGH_FRAC·D (80 %) without
                       falling back below the low mark; its time runs from the last frame below the low mark to
                       the first frame above the high mark (the 20-80 % rise time, as in instrumented sit-to-stand
                       tests), s;
    mean_s           = mean transition time, s; count = number of transitions.
None when no transition is found.
"""

from __future__ import annotations

import numpy as np

from kinect_agent.analysis import series
from kinect_agent.skeleton import INDEX

MIN_RISE_M = 0.15
LOW_FRAC, HIGH_FRAC = 0.2, 0.8


def rise_times(t: np.ndarray, height: np.ndarray) -> list[float]:
    """Returns the 20-80 % rise time of every sit-to-stand transition, s; t, height: (T,) s and m (smoothed)."""
    finite = height[np.isfinite(height)]
    if finite.size < 3:
        return []
    seated, standing = np.percentile(finite, [5.0, 95.0])
    D = standing - seated
    if D < MIN_RISE_M:
        return []
    low, high = seated + LOW_FRAC * D, seated + HIGH_FRAC * D
    times, last_low = [], None
    for i, h in enumerate(height):
        if h < low:
            last_low = i
        elif h > high and last_low is not None:
            times.append(float(t[i] - t[last_low]))
            last_low = None
    return times


def sit_to_stand(t: np.ndarray, positions: np.ndarray) -> dict[str, float | int] | None:
    """Returns {"mean_s", "count"} of the sit-to-stand transitions in positions (T, J, 3) m, or None."""
    height = series.smooth(t, positions[:, INDEX["ROOT"], 1])
    times = rise_times(np.asarray(t, dtype=np.float64), height)
    if not times:
        return None
    return {"mean_s": round(float(np.mean(times)), 3), "count": len(times)}
