"""Reference estimates that know the truth: how much of a simulated Kinect's error any temporal filter can remove.

oracle_clean: the truth plus the Kinect's error with every tracking-loss outlier and untracked joint-frame replaced
    by the error interpolated in time from its clean neighbours — perfect outlier removal and no smoothing at all.
oracle_lowpass: the same error, then low-passed (zero-phase Butterworth, 2nd order) at a cutoff — an ideal filter
    that passes the motion untouched and removes all of the clean error above the cutoff. Human exercise motion
    reaches 2-3 Hz (kicks, arm circles), so no filter that follows it can do better than oracle_lowpass at ~2 Hz.
Neither is a method: both need the truth and the simulated outlier mask.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import butter, filtfilt

from kinect_agent.skeleton import NOT_TRACKED


def clean_error(measured: np.ndarray, state: np.ndarray, truth: np.ndarray, outliers: np.ndarray) -> np.ndarray:
    """Returns the Kinect's clean error (T, J, 3) m: measured − truth, with outlier, untracked and NaN joint-frames
    linearly interpolated in time from the clean ones (held at the ends; 0 for a joint never clean).

    measured, truth: (T, J, 3) m, camera frame (measured NaN = untracked); state: (T, J) Kinect state;
    outliers: (T, J) bool, the simulated tracking-loss mask."""
    err = measured - truth
    bad = outliers | (state == NOT_TRACKED) | ~np.all(np.isfinite(err), axis=-1)
    frames = np.arange(len(err))
    out = np.zeros_like(err)
    for j in range(err.shape[1]):
        ok = ~bad[:, j]
        if ok.any():
            for axis in range(3):
                out[:, j, axis] = np.interp(frames, frames[ok], err[ok, j, axis])
    return out


def oracle_estimate(
    measured: np.ndarray,
    state: np.ndarray,
    truth: np.ndarray,
    outliers: np.ndarray,
    rate_hz: float,
    cutoff_hz: float | None = None,
) -> np.ndarray:
    """Returns truth + the clean error (T, J, 3) m, low-passed at cutoff_hz when given (None: not smoothed).

    Arguments as clean_error; rate_hz: the frame rate, Hz (the cutoff must be below half of it)."""
    err = clean_error(measured, state, truth, outliers)
    if cutoff_hz is not None:
        if not 0 < cutoff_hz < rate_hz / 2:
            raise ValueError(f"cutoff_hz must be in (0, {rate_hz / 2}) Hz, got {cutoff_hz}")
        b, a = butter(2, cutoff_hz / (rate_hz / 2))
        err = filtfilt(b, a, err, axis=0, padlen=min(3 * max(len(a), len(b)), len(err) - 1))
    return truth + err
