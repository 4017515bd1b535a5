"""95 % intervals of the range-of-motion metrics and of the repetition count, from the per-frame angle SDs.

Inputs: the clinical angles the server measures (range_of_motion.py: from smoothed filtered positions) and, per
frame, the SD of each angle's error as the agent stored it (kinect_agent.processing.uncertainty.angle_sd: the
smoother's covariance propagated through FK and the angle definitions, times a measured inflation).

Error model of one metric m (degrees), measured on simulated sessions with known truth (bench/uncertainty.py):
    m̂ − m_true ~ N(0, σ_frames² + b²)
    σ_frames   the per-frame SD at the frames that set the metric: the mean SD over the frames within 2 % of the
               range from the 99th (max_deg, the peak) or the 1st percentile (min_deg); for range_deg the two
               combined, sqrt(σ_hi² + σ_lo²) (the random error at the two turning points is nearly independent:
               they lie more than the jitter's correlation time, 0.2 s, apart)
    b          the systematic part the covariance cannot know (Kinect's joint-placement bias seen through the
               angle definitions; e.g. a straight elbow reads bent), per angle and per metric (min_deg, max_deg,
               range_deg), fitted on training motions, views and seeds so that 95 % of
               the training intervals cover the truth, and validated on other motions, views and seeds
               (bench/README.md, tests/backend/analysis/test_intervals_calibration.py).
    interval   m̂ ± 1.96 · sqrt(σ_frames² + b²); a range never below 0. None for NO_INTERVAL angles and for ranges
               of a full turn or more.

Repetition count: counted again on perturbed angles (each defining angle + its SD × unit-variance noise smoothed
like the filtered angles' error, NOISE_SMOOTH_S; n_draws draws, a fixed seed); the interval is [min, max] of the
counts and the count is ambiguous when they differ.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d

from backend.analysis.range_of_motion import HIGH_PCT, LOW_PCT
from kinect_agent.analysis import series
from kinect_agent.analysis.repetitions import RepetitionParams, count_repetitions

Z95 = 1.959964
EDGE_FRACTION = 0.02  # frames within this fraction of the range from a percentile set that end's SD
NOISE_SMOOTH_S = 0.2  # s; the filtered angles' error correlates 0.93 / 0.75 / 0.24 at 0.1 / 0.2 / 0.5 s (training
# sessions of bench/uncertainty.py), as Gaussian-smoothed noise of SD 0.2 s does (0.94 / 0.78 / 0.21)
COUNT_DRAWS = 20
# No interval: shoulder rotation is undefined with a straight elbow (its error reaches ±180° in simulated sessions),
# and a range of a full turn or more means the angle spun through its ±180° seam (an ill-defined range).
NO_INTERVAL = ("shoulder_rotation_L", "shoulder_rotation_R")
MAX_RANGE_DEG = 360.0
# b (degrees) per angle: (min_deg, max_deg, range_deg), fitted by bench/uncertainty.py (bench/README.md, "Uncertainty").
# Both sides share one fit (pooled); the shoulder rotations have none (NO_INTERVAL).
_PAIRS: dict[str, tuple[float, float, float]] = {
    "elbow_flexion": (0.0, 23.0, 16.4),
    "knee_flexion": (1.7, 28.7, 25.6),
    "shoulder_flexion": (7.1, 21.4, 6.6),
    "shoulder_abduction": (16.7, 9.7, 25.7),
    "hip_flexion": (13.0, 4.5, 3.4),
    "hip_abduction": (3.0, 0.0, 0.0),
}
SYSTEMATIC_DEG: dict[str, tuple[float, float, float]] = {
    **{f"{pair}_{side}": b for pair, b in _PAIRS.items() for side in ("L", "R")},
    "trunk_flexion": (0.0, 2.6, 0.0),
    "trunk_lateral_flexion": (31.0, 34.0, 6.3),
}


@dataclass(frozen=True)
class CountInterval:
    """The repetition count's 95 % interval: low..high counts under perturbed angles; ambiguous when they differ."""

    low: int
    high: int

    @property
    def ambiguous(self) -> bool:
        """True when the perturbed counts differ."""
        return self.low != self.high

    def to_dict(self) -> dict[str, int | bool]:
        """Returns {"low", "high", "ambiguous"}."""
        return {"low": self.low, "high": self.high, "ambiguous": self.ambiguous}


@dataclass(frozen=True)
class Edges:
    """The ends of one angle's range (1st and 99th percentiles, degrees) and the per-frame SD at each (degrees)."""

    low: float
    high: float
    sd_low: float
    sd_high: float


def _edge_sd(y: np.ndarray, sd: np.ndarray, level: float, span: float, upper: bool) -> float:
    near = y >= level - EDGE_FRACTION * span if upper else y <= level + EDGE_FRACTION * span
    vals = sd[near & np.isfinite(sd)]
    return float(np.mean(vals)) if vals.size else float(np.nanmedian(sd))


def edges(t: np.ndarray, x: np.ndarray, sd: np.ndarray) -> Edges | None:
    """Returns the Edges of one angle, or None when x or sd has no finite value.

    t: (T,) s. x: (T,) degrees, the angle as range_of_motion measures it (presmoothed). sd: (T,) degrees.
    """
    t = np.asarray(t, dtype=np.float64)
    if np.shape(x) != t.shape or np.shape(sd) != t.shape:
        raise ValueError(f"t, x and sd must share the shape (T,), got {t.shape}, {np.shape(x)}, {np.shape(sd)}")
    y = series.smooth(t, np.asarray(x, dtype=np.float64), median_s=0.0, smooth_s=0.0)
    sd = np.asarray(sd, dtype=np.float64)
    if not (y.size and np.all(np.isfinite(y)) and np.isfinite(sd).any()):
        return None
    lo, hi = np.percentile(y, [LOW_PCT, HIGH_PCT])
    span = max(float(hi - lo), 1e-9)
    return Edges(float(lo), float(hi), _edge_sd(y, sd, lo, span, False), _edge_sd(y, sd, hi, span, True))


def _interval(centre: float, sd: float, floor: float | None = None) -> list[float]:
    lo, hi = centre - Z95 * sd, centre + Z95 * sd
    if floor is not None:
        lo = max(lo, floor)
    return [round(lo, 1), round(hi, 1)]


def angle_intervals(t: np.ndarray, x: np.ndarray, sd: np.ndarray, name: str) -> dict[str, list[float]] | None:
    """Returns {"min_deg": [lo, hi], "max_deg": [lo, hi], "range_deg": [lo, hi]} (95 %, degrees) of one angle.

    t: (T,) s. x: (T,) degrees, the angle as range_of_motion measures it (presmoothed). sd: (T,) degrees, its
    per-frame SD. name: the angle (for its systematic part). None when x or sd has no finite value, for the angles
    of NO_INTERVAL and for a range of MAX_RANGE_DEG or more.
    """
    e = edges(t, x, sd)
    if e is None or name in NO_INTERVAL or e.high - e.low >= MAX_RANGE_DEG:
        return None
    b_min, b_max, b_range = SYSTEMATIC_DEG.get(name, (0.0, 0.0, 0.0))
    return {
        "min_deg": _interval(e.low, float(np.hypot(e.sd_low, b_min))),
        "max_deg": _interval(e.high, float(np.hypot(e.sd_high, b_max))),
        "range_deg": _interval(e.high - e.low, float(np.sqrt(e.sd_high**2 + e.sd_low**2 + b_range**2)), floor=0.0),
    }


def covers(interval: list[float], true: float, kind: str) -> bool:
    """True when a 95 % interval [lo, hi] (rounded to 0.1°) of metric `kind` ("min_deg", "max_deg", "range_deg")
    holds the value `true`; the ends of a range are angles, compared modulo a turn."""
    lo, hi = interval
    if kind == "range_deg":
        return lo - 0.05 <= true <= hi + 0.05
    off = (0.5 * (lo + hi) - true + 180.0) % 360.0 - 180.0
    return abs(off) <= 0.5 * (hi - lo) + 0.05


def rom_intervals(
    t: np.ndarray, angles: dict[str, np.ndarray], sd: dict[str, np.ndarray]
) -> dict[str, dict[str, list[float]] | None]:
    """Returns {angle: angle_intervals(...)} for every angle present in both angles and sd ({name: (T,) degrees})."""
    return {name: angle_intervals(t, angles[name], sd[name], name) for name in angles if name in sd}


def _smooth_noise(rng: np.random.Generator, T: int, n: int, dt: float) -> np.ndarray:
    """Returns (T, n) unit-variance Gaussian noise smoothed by a Gaussian of SD NOISE_SMOOTH_S (at frame interval dt
    s): correlation exp(−Δ² / (4 · NOISE_SMOOTH_S²)) between frames Δ s apart."""
    z = gaussian_filter1d(rng.standard_normal((T, n)), NOISE_SMOOTH_S / dt, axis=0, mode="reflect")
    return z / np.maximum(np.std(z, axis=0, keepdims=True), 1e-12)


def count_interval(
    t: np.ndarray,
    angles: dict[str, np.ndarray],
    sd: dict[str, np.ndarray],
    names: tuple[str, ...],
    params: RepetitionParams | None = None,
    *,
    n_draws: int = COUNT_DRAWS,
    seed: int = 0,
) -> CountInterval:
    """Returns the repetition count's interval: the counts of n_draws perturbed copies of the defining angles.

    angles: {name: (T,) degrees} as count_repetitions takes them; sd: {name: (T,) degrees} their per-frame SDs
    (a name without one is not perturbed). Also counts the unperturbed angles (the interval always holds it).
    """
    t = np.asarray(t, dtype=np.float64)
    rng = np.random.default_rng(seed)
    counts = [len(count_repetitions(t, angles, names, params).repetitions)]
    dt = series.frame_interval(t)
    for _ in range(n_draws):
        z = _smooth_noise(rng, t.shape[0], len(names), dt)
        noisy = dict(angles)
        for k, name in enumerate(names):
            s = sd.get(name)
            if s is not None:
                noisy[name] = np.asarray(angles[name]) + np.nan_to_num(np.asarray(s), nan=0.0) * z[:, k]
        counts.append(len(count_repetitions(t, noisy, names, params).repetitions))
    return CountInterval(min(counts), max(counts))


__all__ = ["SYSTEMATIC_DEG", "CountInterval", "Edges", "angle_intervals", "edges", "count_interval", "rom_intervals"]
