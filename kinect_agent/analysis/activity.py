"""Activity over a session: moving time and rest, tempo, and fatigue across repetitions.

Definitions:
    speed(t)        = the largest joint speed in that frame, m/s, from smoothed positions (series.smooth_positions,
                      Gaussian SD 0.1 s) by differences to the next frame (the last frame repeats the one before);
    moving frames   = speed ≥ MOVING_M_S (0.15 m/s; Kinect jitter after smoothing stays well below it, a slow
                      exercise movement well above); runs of moving or resting frames shorter than MIN_RUN_S
                      (0.3 s) take the state of their surroundings;
    moving_time_s   = Σ frame intervals of moving frames; rest_time_s = duration − moving_time_s;
    tempo_s_per_rep = median interval between the starts of consecutive repetitions (cadence, pauses included);
                      the single repetition's duration when there is one; None with none;
    fatigue         = least-squares slopes, over the repetition index, of amplitude and of duration, each in
                      percent of its mean per repetition (negative amplitude slope = the range shrinks, positive
                      duration slope = the movement slows); None values with fewer than 3 repetitions.
"""

from __future__ import annotations

import numpy as np

from kinect_agent.analysis import series
from kinect_agent.analysis.repetitions import Repetition

MOVING_M_S = 0.15
MIN_RUN_S = 0.3


def max_joint_speed(t: np.ndarray, smoothed: np.ndarray) -> np.ndarray:
    """Returns (T,) m/s, the fastest joint's speed per frame; smoothed: (T, J, 3) m; t: (T,) s."""
    if t.shape[0] < 2:
        return np.zeros(t.shape[0])
    speed = series.norm3(np.diff(smoothed, axis=0)) / np.diff(t)[:, None]  # (T-1, J)
    speed = np.concatenate((speed, speed[-1:]), axis=0)
    return np.nanmax(np.where(np.isfinite(speed), speed, -np.inf), axis=1).clip(min=0.0)


def _absorb_short_runs(state: np.ndarray, min_len: int) -> np.ndarray:
    """Returns state (T,) bool with runs shorter than min_len frames flipped (shortest first, one pass)."""
    out = state.copy()
    if min_len <= 1 or out.size == 0:
        return out
    edges = np.flatnonzero(np.diff(out.astype(np.int8))) + 1
    starts = np.concatenate(([0], edges))
    stops = np.concatenate((edges, [out.size]))
    for a, b in zip(starts, stops, strict=True):
        if b - a < min_len and a > 0 and b < out.size:
            out[a:b] = ~out[a]
    return out


def moving_time(t: np.ndarray, smoothed: np.ndarray) -> tuple[float, float]:
    """Returns (moving_time_s, rest_time_s) of a session; t: (T,) s, smoothed: (T, J, 3) m."""
    if t.shape[0] < 2:
        return 0.0, 0.0
    moving = max_joint_speed(t, smoothed) >= MOVING_M_S
    dt = np.diff(t)
    min_len = max(1, int(round(MIN_RUN_S / float(np.median(dt)))))
    moving = _absorb_short_runs(moving, min_len)
    frame_dt = np.concatenate((dt, [0.0]))
    total = float(t[-1] - t[0])
    active = float(np.sum(frame_dt[moving]))
    return round(active, 2), round(total - active, 2)


def tempo(reps: list[Repetition]) -> float | None:
    """Returns the median start-to-start interval of the repetitions, s (see module doc)."""
    if not reps:
        return None
    if len(reps) == 1:
        return round(reps[0].duration_s, 2)
    return round(float(np.median(np.diff([r.start_s for r in reps]))), 2)


def _slope_pct(values: np.ndarray) -> float:
    mean = float(np.mean(values))
    if mean == 0:
        return 0.0
    slope = np.polyfit(np.arange(values.size, dtype=np.float64), values, 1)[0]
    return round(float(100.0 * slope / mean), 2)


def fatigue(reps: list[Repetition]) -> dict[str, float | None]:
    """Returns {"amplitude_slope_pct_per_rep", "duration_slope_pct_per_rep"} (see module doc)."""
    if len(reps) < 3:
        return {"amplitude_slope_pct_per_rep": None, "duration_slope_pct_per_rep": None}
    return {
        "amplitude_slope_pct_per_rep": _slope_pct(np.array([r.amplitude_deg for r in reps])),
        "duration_slope_pct_per_rep": _slope_pct(np.array([r.duration_s for r in reps])),
    }
