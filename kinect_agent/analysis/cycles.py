"""The cycle of a repeated movement, read from one excursion series: its period and its typical amplitude.

An excursion series e: (T,) degrees, ≥ 0 (distance of a smoothed angle from its rest level, repetitions.detect), at
times t: (T,) s. Definitions:
    period P  = the lag of the autocorrelation's first peak (prominence ≥ MIN_AC_PROMINENCE, so not a ripple of
                its decay) at least 0.8 times as high as its highest, between MIN_PERIOD_S and a third of the
                recording (so at least three cycles support it), when that peak's correlation is at least
                MIN_CORRELATION; else None (one movement, a pause, or no repeated movement). Peaks, not the
                first zero crossing: a drifting rest level keeps the correlation positive;
    peaks     = the local maxima of e with a topographic prominence (scipy.signal.peak_prominences: height above
                the higher of the two lowest points separating it from higher ground) of at least
                FLOOR_FRAC × (p98 − p2) of e;
    amplitude A = the median prominence of the N most prominent peaks, N = max(1, round(duration / P)): the height
                of a typical cycle. Unlike the range p98 − p2, one mistracked spike or a few very deep repetitions
                move it little, and smaller repetitions of a patient who does them badly do not lower the range
                the others are judged against. Without a period, A = the largest prominence (the range of the one
                movement).
    baseline  = the grey opening of e over BASELINE_PERIODS × P, and over at least twice the widest of the N most
                prominent peaks at half their prominence (so that no excursion is wider than the opening and none
                is taken for rest; widths from the prominence, so a drifting rest does not widen them): the lower
                envelope, the rest level between cycles, which drifts when the patient shifts the idle posture;
                without a period, 0.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import grey_opening
from scipy.signal import find_peaks, peak_widths

from kinect_agent.analysis.series import frame_interval

MIN_PERIOD_S = 0.6
MIN_CORRELATION = 0.3
MIN_AC_PROMINENCE = 0.1
FLOOR_FRAC = 0.05
BASELINE_PERIODS = 1.5


@dataclass(frozen=True)
class Cycle:
    """period_s: P in seconds (None: not periodic); correlation: the autocorrelation at P (0 when None);
    amplitude_deg: A in degrees; n_cycles: N, the cycles the recording holds at that period; top_frames: the
    frames of the N most prominent peaks, most prominent first (empty when not periodic)."""

    period_s: float | None
    correlation: float
    amplitude_deg: float
    n_cycles: int
    top_frames: tuple[int, ...] = ()


def autocorrelation(x: np.ndarray) -> np.ndarray:
    """Returns (T,) the unbiased, normalised autocorrelation of x: (T,) (mean removed; ac[0] = 1; zeros if x is
    constant)."""
    x = np.asarray(x, dtype=np.float64) - np.mean(x)
    n = x.shape[0]
    f = np.fft.rfft(x, 2 * n)
    ac = np.fft.irfft(f * np.conj(f))[:n] / (n - np.arange(n))
    return ac / ac[0] if ac[0] > 0 else np.zeros(n)


def period(t: np.ndarray, e: np.ndarray) -> tuple[float | None, float]:
    """Returns (P in seconds or None, the autocorrelation at P) of e: (T,) at t: (T,) s (module doc)."""
    dt = frame_interval(t)
    n = e.shape[0]
    top = n // 3
    lo = max(1, int(np.ceil(MIN_PERIOD_S / dt)))
    if top <= lo:
        return None, 0.0
    ac = autocorrelation(e)[:top]
    frames, props = find_peaks(ac, prominence=MIN_AC_PROMINENCE)
    keep = frames >= lo
    frames, heights = frames[keep], ac[frames[keep]]
    if frames.size == 0 or heights.max() < MIN_CORRELATION:
        return None, 0.0
    # the first peak nearly as high as the highest: the fundamental, not a multiple of it
    k = int(frames[np.argmax(heights >= 0.8 * heights.max())])
    return float(k * dt), float(ac[k])


def prominences(e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Returns (frames, prominences in degrees) of the peaks of e: (T,) (module doc), most prominent first."""
    finite = e[np.isfinite(e)]
    if finite.size < 3:
        return np.zeros(0, dtype=int), np.zeros(0)
    lo, hi = np.percentile(finite, [2.0, 98.0])
    padded = np.concatenate(([finite.min()], e, [finite.min()]))  # a peak at either end of the recording is a peak too
    frames, props = find_peaks(padded, prominence=max(FLOOR_FRAC * (hi - lo), 1e-9))
    order = np.argsort(props["prominences"])[::-1]
    return frames[order] - 1, props["prominences"][order]


def cycle(t: np.ndarray, e: np.ndarray) -> Cycle:
    """Returns the Cycle of the excursion series e: (T,) degrees at times t: (T,) s (module doc)."""
    frames, prom = prominences(e)
    if prom.size == 0:
        return Cycle(None, 0.0, 0.0, 0)
    p, corr = period(t, e)
    if p is None:
        return Cycle(None, 0.0, float(prom[0]), 1)
    n = max(1, int(round((t[-1] - t[0]) / p)))
    return Cycle(p, corr, float(np.median(prom[:n])), n, tuple(int(f) for f in frames[:n]))


def baseline(t: np.ndarray, e: np.ndarray, cyc: Cycle) -> np.ndarray:
    """Returns (T,) the rest level of e: (T,) under its cycles (module doc), zeros without a period.

    cyc: cycle(t, e) of this same e (its top_frames are e's peaks).
    """
    if cyc.period_s is None:
        return np.zeros_like(e)
    top = np.asarray(cyc.top_frames, dtype=np.int64) + 1  # in the padded series prominences() found them in
    padded = np.concatenate(([e.min()], e, [e.min()]))
    widest = float(peak_widths(padded, top, rel_height=0.5)[0].max()) if top.size else 0.0
    size = max(3, int(round(BASELINE_PERIODS * cyc.period_s / frame_interval(t))), int(2 * widest)) | 1
    return grey_opening(e, size=size, mode="nearest")
