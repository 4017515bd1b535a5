"""Zero-lag low-pass Butterworth filter, the biomechanics default for marker and skeleton data.

Reference: D. A. Winter, "Biomechanics and Motor Control of Human Movement", 4th ed. (2009), §3.4.4: a
second-order Butterworth run forwards and backwards (scipy.signal.filtfilt) has zero phase lag and is a
fourth-order filter whose -3 dB point lies below the design cutoff; Winter's correction divides the (pre-warped)
design cutoff by C = (2^(1/n) − 1)^(1/4) = 0.802 for n = 2 passes, tan(π·f_design/fs) = tan(π·cutoff/fs) / C, so
that the *zero-lag* filter is -3 dB at cutoff_hz (6 Hz at 30 Hz: design 7.03 Hz).
NaN gaps (untracked joint-frames) are linearly interpolated in time before filtering (ends held).
"""

from __future__ import annotations

import numpy as np
from scipy.signal import butter, filtfilt

from bench.baselines._common import check_input, fill_gaps, sample_rate

CUTOFF_HZ = 6.0  # the usual cutoff for human movement (Winter 2009)
ORDER = 2  # per pass; the zero-lag filter is of order 4


def winter_correction(passes: int = 2) -> float:
    """Returns C = (2^(1/passes) − 1)^(1/4): the design cutoff is cutoff / C (Winter 2009, §3.4.4)."""
    return float((2.0 ** (1.0 / passes) - 1.0) ** 0.25)


def butterworth(
    t: np.ndarray, positions: np.ndarray, cutoff_hz: float = CUTOFF_HZ, order: int = ORDER, corrected: bool = True
) -> np.ndarray:
    """Returns positions (T, ...) m low-passed at cutoff_hz with zero lag; gaps interpolated first.

    t: (T,) s, uniform sampling assumed (rate = 1 / median interval). positions: (T, ...) m, NaN = missing.
    corrected: apply Winter's two-pass cutoff correction (the combined filter is -3 dB at cutoff_hz).
    """
    shape = np.shape(positions)
    t, x = check_input(t, positions)
    if not cutoff_hz > 0:
        raise ValueError(f"cutoff_hz must be > 0, got {cutoff_hz!r}")
    fs = sample_rate(t)
    if not cutoff_hz < fs / 2:
        raise ValueError(f"cutoff {cutoff_hz:.2f} Hz must be below Nyquist {fs / 2:.2f} Hz")
    design = cutoff_hz
    if corrected:
        design = fs / np.pi * np.arctan(np.tan(np.pi * cutoff_hz / fs) / winter_correction(2))
    x = fill_gaps(t, x)
    b, a = butter(order, design / (fs / 2))
    ok = np.all(np.isfinite(x), axis=0)
    out = x.copy()
    if t.shape[0] > 3 * max(len(a), len(b)):
        out[:, ok] = filtfilt(b, a, x[:, ok], axis=0)
    return out.reshape(shape)
