"""Time alignment of a Kinect recording and a motion-capture recording that run at different rates.

The lag is found where the summed speed of the matching joints correlates best (speed does not depend on the
unknown rigid transform between the two frames), over +-max_lag_s in LAG_STEP_S steps; a fine search then takes the
lag with the lowest trimmed registration RMS within +-2 Kinect frames of it. Mocap is resampled (linear
interpolation) at the Kinect frame times + lag; the Kinect frames stay as recorded.
Convention: mocap time = Kinect time + lag.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from kinect_agent.evaluation.register import Registration, register, robust_kabsch, trimmed_rms
from kinect_agent.processing.outliers import running_median
from kinect_agent.recording import Recording
from kinect_agent.skeleton import NOT_TRACKED

MAX_LAG_S = 2.0
LAG_STEP_S = 1.0 / 120.0
MEDIAN_S = 0.3  # running-median window applied before the speeds are taken
MIN_OVERLAP = 0.5  # fraction of the Kinect frames that must have mocap beside them at a candidate lag


def interpolate(t_src: np.ndarray, p_src: np.ndarray, t_new: np.ndarray) -> np.ndarray:
    """Returns p_src (T, ...) linearly interpolated at t_new (N,) s; NaN outside [t_src[0], t_src[-1]] and next to
    NaN samples. t_src: (T,) s, increasing."""
    x = np.asarray(p_src, dtype=np.float64)
    i1 = np.clip(np.searchsorted(t_src, t_new), 1, len(t_src) - 1)
    i0 = i1 - 1
    w = ((t_new - t_src[i0]) / (t_src[i1] - t_src[i0])).reshape((-1,) + (1,) * (x.ndim - 1))
    out = x[i0] * (1.0 - w) + x[i1] * w
    out[(t_new < t_src[0] - 1e-9) | (t_new > t_src[-1] + 1e-9)] = np.nan
    return out


def speed_signal(p: np.ndarray, joints: np.ndarray, rate_hz: float) -> np.ndarray:
    """Returns (T,) m/s: the summed speed of the joints (indices) of p (T, J, 3) m, smoothed over 5 frames; NaN kept."""
    v = np.linalg.norm(np.diff(p[:, joints], axis=0), axis=-1).sum(axis=-1) * rate_hz
    v = np.concatenate([v[:1], v])
    kernel = np.ones(5) / 5.0
    return np.convolve(np.nan_to_num(v, nan=0.0), kernel, mode="same") + np.where(np.isfinite(v), 0.0, np.nan)


def frame_rate(rec: Recording) -> float:
    """Returns the recording's frame rate (Hz) from its median frame interval."""
    return 1.0 / float(np.median(np.diff(rec.t))) if rec.n_frames > 1 else float(rec.meta.rate_hz or 30.0)


def measured(rec: Recording) -> np.ndarray:
    """Returns (T, J, 3) m: the positions with not-tracked joint-frames set to NaN."""
    return np.where((rec.state == NOT_TRACKED)[..., None], np.nan, rec.positions)


def despiked(rec: Recording, joints: np.ndarray, window_s: float = MEDIAN_S) -> np.ndarray:
    """Returns (T, J', 3) m: the joints (indices) of rec, untracked NaN, through a centred running median of
    window_s seconds (tracking-loss bursts would otherwise dominate the summed speed; a centred median adds no lag);
    window_s = 0: as measured."""
    if window_s <= 0.0:
        return measured(rec)[:, joints]
    w = max(3, int(round(window_s * frame_rate(rec))) | 1)
    return running_median(measured(rec)[:, joints], w)


def xcorr_lag(
    kinect: Recording, mocap: Recording, joints: np.ndarray, max_lag_s: float, despike_s: float = MEDIAN_S
) -> tuple[float, float]:
    """Returns (lag s, correlation) maximising the correlation of the summed joint speeds; joints (J,) bool;
    despike_s: running-median window applied before the speeds (despiked)."""
    t_k, rate = kinect.t, frame_rate(kinect)
    idx = np.flatnonzero(joints)
    all_joints = np.arange(len(idx))
    s_k = speed_signal(despiked(kinect, idx, despike_s), all_joints, rate)
    p_m = despiked(mocap, idx, despike_s)
    best, best_c = 0.0, -np.inf
    for lag in np.arange(-max_lag_s, max_lag_s + 1e-9, LAG_STEP_S):
        s_m = speed_signal(interpolate(mocap.t, p_m, t_k + lag), all_joints, rate)
        ok = np.isfinite(s_k) & np.isfinite(s_m)
        if ok.sum() < MIN_OVERLAP * len(t_k) or np.std(s_k[ok]) == 0 or np.std(s_m[ok]) == 0:
            continue
        c = float(np.corrcoef(s_k[ok], s_m[ok])[0, 1])
        if c > best_c:
            best, best_c = float(lag), c
    return best, best_c


def registration_rms(
    t_k: np.ndarray,
    p_k: np.ndarray,
    mocap: Recording,
    lag: float,
    joints: np.ndarray,
    min_overlap: float = 0.0,
    rigid: bool = True,
) -> float:
    """Returns the trimmed registration RMS (m) of mocap at t_k + lag onto p_k (T, J, 3) m; inf with too little
    overlap (under 30 frames or under min_overlap of the frames)."""
    truth = interpolate(mocap.t, mocap.positions, t_k + lag)[:, joints]
    n = np.sum(np.all(np.isfinite(truth), axis=(1, 2)))
    if n < max(30, min_overlap * len(t_k)):
        return np.inf
    if not rigid:
        return trimmed_rms(truth.reshape(-1, 3), p_k[:, joints].reshape(-1, 3))
    return robust_kabsch(truth.reshape(-1, 3), p_k[:, joints].reshape(-1, 3))[2]


def fine_lag(
    kinect: Recording,
    mocap: Recording,
    joints: np.ndarray,
    around: float,
    frames: slice = slice(None),
    rigid: bool = True,
) -> float:
    """Returns the lag (s) within around +- 2 Kinect frames minimising the trimmed registration RMS (over `frames`)."""
    half_width = 2.0 / frame_rate(kinect)
    lags = around + np.arange(-half_width, half_width + 1e-9, LAG_STEP_S)
    t_k, p_k = kinect.t[frames], measured(kinect)[frames]
    rms = [registration_rms(t_k, p_k, mocap, lag, joints, rigid=rigid) for lag in lags]
    return float(lags[int(np.argmin(rms))])


def rms_lag(kinect: Recording, mocap: Recording, joints: np.ndarray, max_lag_s: float, rigid: bool = True) -> float:
    """Returns the lag (s, over +-max_lag_s in Kinect-frame steps) minimising the trimmed registration RMS: an
    estimate independent of the speed correlation."""
    lags = np.arange(-max_lag_s, max_lag_s + 1e-9, 1.0 / frame_rate(kinect))
    p_k = measured(kinect)
    rms = [registration_rms(kinect.t, p_k, mocap, lag, joints, MIN_OVERLAP, rigid) for lag in lags]
    return float(lags[int(np.argmin(rms))])


@dataclass(frozen=True)
class Alignment:
    """Mocap -> Kinect: truth(t_k) = registration.apply(mocap(t_k + lag_s)).

    lag_xcorr_s, xcorr: the coarse speed-correlation lag and its correlation; lag_rms_s: the independent lag of the
    lowest registration RMS (None when not computed); lag_halves_s: the fine lag refitted on each half of the Kinect
    frames (a drifting clock or a wrong rate makes them differ).
    """

    lag_s: float
    lag_xcorr_s: float
    xcorr: float
    lag_rms_s: float | None
    lag_halves_s: tuple[float, float]
    registration: Registration

    @property
    def R(self) -> np.ndarray:
        """Returns the registration's rotation (3, 3)."""
        return self.registration.R

    @property
    def t(self) -> np.ndarray:
        """Returns the registration's translation (3,) m."""
        return self.registration.t

    @property
    def rms_m(self) -> float:
        """Returns the registration's trimmed RMS residual, m."""
        return self.registration.rms_m

    def truth(self, kinect: Recording, mocap: Recording) -> np.ndarray:
        """Returns the mocap joints (T, J, 3) m at the Kinect frames, Kinect camera frame; NaN outside the overlap."""
        return self.registration.apply(interpolate(mocap.t, mocap.positions, kinect.t + self.lag_s))


def align(
    kinect: Recording,
    mocap: Recording,
    joints: np.ndarray,
    max_lag_s: float = MAX_LAG_S,
    check: bool = True,
    rigid: bool = True,
    despike_s: float = MEDIAN_S,
) -> Alignment:
    """Finds the lag and the rigid transform taking mocap (any rate) onto the Kinect frames, using the joints (J,) bool.

    check: also the independent registration-RMS lag (rms_lag), for refusing pairs whose two estimates disagree.
    rigid=False: mocap is already in the Kinect camera frame (calibrated); only the lag is estimated.
    despike_s: running-median window before the speeds (0: the speeds as measured, as bench/README.md's runs).
    """
    coarse, c = xcorr_lag(kinect, mocap, joints, max_lag_s, despike_s)
    lag = fine_lag(kinect, mocap, joints, coarse, rigid=rigid)
    half = kinect.n_frames // 2
    halves = (
        fine_lag(kinect, mocap, joints, lag, slice(0, half), rigid),
        fine_lag(kinect, mocap, joints, lag, slice(half, None), rigid),
    )
    lag_rms = rms_lag(kinect, mocap, joints, max_lag_s, rigid) if check else None
    truth = interpolate(mocap.t, mocap.positions, kinect.t + lag)
    return Alignment(lag, coarse, c, lag_rms, halves, register(truth, measured(kinect), joints, rigid))
