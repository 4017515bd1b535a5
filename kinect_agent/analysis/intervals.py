"""95 % intervals of the range-of-motion metrics and of the repetition count, from the per-frame angle SDs.

Inputs: the clinical angles the server measures (range_of_motion.py: from smoothed filtered positions) and, per
frame, the SD of each angle's error as the agent stored it (kinect_agent.processing.uncertainty.angle_sd: the
smoother's covariance propagated through FK and the angle definitions, times a measured inflation).

Error model of one metric m (degrees), measured on simulated sessions with known truth (bench/uncertainty.py):
    m̂ − m_true ~ N(0, (SIGMA_GAIN · σ_frames)² + b²)
    σ_frames   the per-frame SD at the frames that set the metric: the mean SD over the frames within 2 % of the
               range from the 99th (max_deg, the peak) or the 1st percentile (min_deg); for range_deg the two
               combined, sqrt(σ_hi² + σ_lo²) (the random error at the two turning points is nearly independent:
               they lie more than the jitter's correlation time, 0.2 s, apart)
    b          the systematic part the covariance cannot know (Kinect's joint-placement bias seen through the
               angle definitions; e.g. a straight elbow reads bent), from what the server measures in the session:
                   b = g_device · (1 + YAW_GAIN · sin ψ) · sqrt(B² + (TAIL_GAIN · τ)²)
               ψ      the body's yaw to the camera (camera_yaw: the shoulder line against the camera's x axis,
                      0° facing it, 90° side on); Kinect's joint offsets grow as the body turns away
               τ      the tail of the angle's distribution beyond the edge: P99 − P90 (max_deg), P10 − P1 (min_deg),
                      their hypot (range_deg); small where the angle turns smoothly at its ends or stands still,
                      large where filter excursions or an ill-defined angle (hip abduction in a deep squat) set
                      the edge
               B      per angle and metric (min_deg, max_deg, range_deg), both sides pooled
               g_device  DEVICE_GAIN of the session's device (1 for Kinect 2 and any device not listed; Kinect 1
                      larger, fitted on its own training sessions so that 95.5 % of them cover)
               YAW_GAIN, TAIL_GAIN (one per metric) and B are fitted on simulated training sessions (bench/
               uncertainty.py): the gains, on a grid, give the narrowest intervals among those whose
               per-(motion, view) coverage deviates from 95 % (RMS) at most 10 % more than the least deviation on
               the grid; B is one quantile (the same for every angle and metric) of the B each training interval
               needs, set so that 95.5 % of the training intervals cover the truth.
               tests/kinect_agent/analysis/test_intervals_calibration.py holds the coverage on held-out sessions; the
               fits, their data and the measured coverage are in bench/README.md ("Uncertainty: angle SDs and
               95 % intervals" and the sections after it). Limits: B is 0 for all angles but trunk lateral
               flexion, so a bias that holds still (no tail) is not widened for; the constants are fitted on
               Kinect 2, and Kinect 1's minimum covers least.
    interval   m̂ ± 1.96 · sqrt((SIGMA_GAIN · σ_frames)² + b²), then kept to what the angle can be
               (angle_intervals: inside its domain, the ends consistent, a range never below 0 nor above the
               ends allow). None for NO_INTERVAL angles and for ranges of a full turn or more; withheld, with
               the reason in words (withheld_reason), when wider than MAX_WIDTH_DEG, when the angle is defined
               in too few frames or its joints were tracked in too few. The exercise's defining angles take a
               short tail (DEFINING_TAIL_PCT) with their own gains and B: their long tail is their motion.

Repetition count: counted again on perturbed angles (each defining angle + its SD × unit-variance noise smoothed
like the filtered angles' error, NOISE_SMOOTH_S; n_draws draws, a fixed seed); the interval is [min, max] of the
counts and the count is ambiguous when they differ.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d

from kinect_agent import skeleton
from kinect_agent.analysis import reasons as why
from kinect_agent.analysis import series
from kinect_agent.analysis.anatomy import limit_reason
from kinect_agent.analysis.range_of_motion import HIGH_PCT, LOW_PCT
from kinect_agent.analysis.reasons import Reason
from kinect_agent.analysis.repetitions import RepetitionParams, count_repetitions
from kinect_agent.body.angles import DOMAIN_DEG

Z95 = 1.959964
EDGE_FRACTION = 0.02  # frames within this fraction of the range from a percentile set that end's SD
NOISE_SMOOTH_S = 0.2  # s; the filtered angles' error correlates 0.93 / 0.75 / 0.24 at 0.1 / 0.2 / 0.5 s (training
# sessions of bench/uncertainty.py), as Gaussian-smoothed noise of SD 0.2 s does (0.94 / 0.78 / 0.21)
COUNT_DRAWS = 20
# No interval: shoulder rotation is undefined with a straight elbow (its error reaches ±180° in simulated sessions),
# and a range of a full turn or more means the angle spun through its ±180° seam (an ill-defined range).
NO_INTERVAL = ("shoulder_rotation_L", "shoulder_rotation_R")
MAX_RANGE_DEG = 360.0
KINDS = ("min_deg", "max_deg", "range_deg")
# Withheld intervals (withheld_reason): wider than this says nothing a therapist can act on; an angle defined in
# too few frames, or whose joints were tracked in too few, has no edge the data can place.
MAX_WIDTH_DEG = 60.0
RAW_ENVELOPE_PCT = (0.5, 99.5)  # the raw angle's envelope (beyond_raw)
RAW_MARGIN_DEG = 10.0  # degrees the filtered range may pass that envelope before its intervals are withheld
MIN_DEFINED_FRACTION = 0.5
MIN_TRACKED_FRACTION = 0.8
# The systematic part b = (1 + YAW_GAIN · sin ψ) · sqrt(B² + (TAIL_GAIN · τ)²), fitted by bench/uncertainty.py
# (bench/README.md, "Uncertainty"); B (degrees) per angle: (min_deg, max_deg, range_deg), both sides pooled; the
# shoulder rotations have none (NO_INTERVAL). The fitted quantile of B is about the median: the tail term alone
# covers most training intervals, so B is 0 but for trunk lateral flexion, whose error (up to 60° in a squat or an
# elbow flexion) shows no tail.
YAW_GAIN = 1.0
TAIL_GAIN = (1.0, 3.0, 2.0)  # min_deg, max_deg, range_deg
# The per-frame SD at the edge overstates a percentile's random error (the percentile pools many frames): the
# refit of 2026-11-28 on the simulator of issue 24 keeps SIGMA_GAIN of it (grid 0.7 / 0.85 / 1; bench/README.md).
SIGMA_GAIN = 0.85
# b of a device other than the Kinect 2 the constants were fitted on, times its gain (the session's meta.device),
# fitted by `bench/uncertainty.py --device kinect1` on its own training sessions (Kinect 1's errors are larger:
# the paper's tables); devices not listed keep 1 (the Azure Kinect and Femto have no error tables to simulate).
DEVICE_GAIN: dict[str, float] = {"kinect1": 4.05}
TAIL_PCT = (10.0, 90.0)  # τ: the 1st to the 10th and the 90th to the 99th percentile
# The exercise's defining angles (the ones its repetitions move) take a short tail instead: P99 − P90 of an angle that
# moves is mostly its own motion near the turning points (a squat's knee: τ 11°, b 34-67°, while its peak errs at
# most 11°), so their τ runs from the 1st to the 2.5th and the 97.5th to the 99th percentile, with their own gains
# and B (fitted with the others, bench/README.md, "Intervals of the moving angles", 2026-11-28). The other angles
# keep the long tail: there it catches arms that wander while a squat is counted (errors of 50-70°).
DEFINING_TAIL_PCT = (2.5, 97.5)
DEFINING_TAIL_GAIN = (1.0, 2.0, 1.0)  # min_deg, max_deg, range_deg
_DEFINING_PAIRS: dict[str, tuple[float, float, float]] = {
    "elbow_flexion": (0.0, 14.4, 12.3),
    "knee_flexion": (0.0, 0.0, 0.0),
    "shoulder_flexion": (4.4, 12.3, 4.9),
    "shoulder_abduction": (12.4, 3.3, 18.2),
    "hip_flexion": (0.0, 0.5, 0.0),
    "hip_abduction": (0.0, 0.0, 0.0),
}
DEFINING_SYSTEMATIC_DEG: dict[str, tuple[float, float, float]] = {
    f"{pair}_{side}": b for pair, b in _DEFINING_PAIRS.items() for side in ("L", "R")
}
_PAIRS: dict[str, tuple[float, float, float]] = {
    "elbow_flexion": (0.0, 0.0, 0.0),
    "knee_flexion": (0.0, 0.0, 0.0),
    "shoulder_flexion": (0.0, 0.0, 0.0),
    "shoulder_abduction": (0.0, 0.0, 0.0),
    "hip_flexion": (0.0, 0.0, 0.0),
    "hip_abduction": (0.0, 0.0, 0.0),
}
SYSTEMATIC_DEG: dict[str, tuple[float, float, float]] = {
    **{f"{pair}_{side}": b for pair, b in _PAIRS.items() for side in ("L", "R")},
    "trunk_flexion": (0.0, 0.0, 0.0),
    "trunk_lateral_flexion": (1.0, 0.0, 0.0),
}
_SHOULDERS = (skeleton.INDEX["SHO_L"], skeleton.INDEX["SHO_R"])


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
    """The ends of one angle's range (1st and 99th percentiles, degrees), the per-frame SD at each (degrees) and
    the tail beyond each (degrees: tail_low = P10 − P1, tail_high = P99 − P90)."""

    low: float
    high: float
    sd_low: float
    sd_high: float
    tail_low: float
    tail_high: float


def _edge_sd(y: np.ndarray, sd: np.ndarray, level: float, span: float, upper: bool) -> float:
    near = y >= level - EDGE_FRACTION * span if upper else y <= level + EDGE_FRACTION * span
    vals = sd[near & np.isfinite(sd)]
    return float(np.mean(vals)) if vals.size else float(np.nanmedian(sd))


def edges(t: np.ndarray, x: np.ndarray, sd: np.ndarray, tail_pct: tuple[float, float] = TAIL_PCT) -> Edges | None:
    """Returns the Edges of one angle over the frames where it is defined, or None when x or sd has no finite value.

    t: (T,) s. x: (T,) degrees, the angle as range_of_motion measures it (presmoothed; NaN = undefined). sd: (T,)
    degrees. tail_pct: the percentiles the tails run to (TAIL_PCT, or DEFINING_TAIL_PCT for a defining angle).
    """
    t = np.asarray(t, dtype=np.float64)
    if np.shape(x) != t.shape or np.shape(sd) != t.shape:
        raise ValueError(f"t, x and sd must share the shape (T,), got {t.shape}, {np.shape(x)}, {np.shape(sd)}")
    x = np.asarray(x, dtype=np.float64)
    sd = np.asarray(sd, dtype=np.float64)
    defined = np.isfinite(x)
    if not (defined.any() and np.isfinite(sd[defined]).any()):
        return None
    y, sd = x[defined], sd[defined]
    lo, hi, in_lo, in_hi = np.percentile(y, [LOW_PCT, HIGH_PCT, *tail_pct])
    span = max(float(hi - lo), 1e-9)
    return Edges(
        float(lo),
        float(hi),
        _edge_sd(y, sd, lo, span, False),
        _edge_sd(y, sd, hi, span, True),
        float(in_lo - lo),
        float(hi - in_hi),
    )


def camera_yaw(positions: np.ndarray) -> float | None:
    """Returns the body's yaw to the camera, degrees in [0, 90]: 0 facing it (or facing away), 90 side on; None
    when no frame has both shoulders.

    positions: (T, J, 3) metres, camera frame (x to the side, y up, z away), the skeleton's joint order. The
    median over the frames of the angle between the shoulder line (SHO_L − SHO_R) in the camera's horizontal
    (x, z) plane and the x axis. The shoulders rather than the hips: on simulated sessions (Kinect 2) the shoulder
    line reads 2.6 ± 1.2°, 32.5 ± 2.1° and 62.3 ± 2.2° at views 0°, 30° and 60°, the hip line 17 ± 17°, 40 ± 29°
    and 50 ± 30° (Kinect's hip joints sit 0.2 m apart and their offsets turn the line).
    Raises ValueError when positions is not (T, J, 3).
    """
    p = np.asarray(positions, dtype=np.float64)
    if p.ndim != 3 or p.shape[1:] != (skeleton.J, 3):
        raise ValueError(f"positions must be (T, {skeleton.J}, 3), got {p.shape}")
    across = p[:, _SHOULDERS[0]] - p[:, _SHOULDERS[1]]
    ok = np.all(np.isfinite(across), axis=1) & (np.hypot(across[:, 0], across[:, 2]) > 0)
    if not ok.any():
        return None
    psi = np.degrees(np.arctan2(across[ok, 2], across[ok, 0]))
    return float(np.median(np.abs((psi + 90.0) % 180.0 - 90.0)))


def systematic(
    name: str, e: Edges, yaw_deg: float, device: str = "kinect2", defining: bool = False
) -> tuple[float, float, float]:
    """Returns b (degrees) of (min_deg, max_deg, range_deg) of angle `name` with edges e at body yaw yaw_deg, for a
    session of `device` (DEVICE_GAIN); `defining`: the angle defines the exercise's repetitions (e's tails then run
    to DEFINING_TAIL_PCT; DEFINING_TAIL_GAIN and DEFINING_SYSTEMATIC_DEG apply)."""
    table, gains = (DEFINING_SYSTEMATIC_DEG, DEFINING_TAIL_GAIN) if defining else (SYSTEMATIC_DEG, TAIL_GAIN)
    b_min, b_max, b_range = table.get(name, (0.0, 0.0, 0.0))
    gain = (1.0 + YAW_GAIN * abs(float(np.sin(np.radians(yaw_deg))))) * DEVICE_GAIN.get(device, 1.0)
    tails = (e.tail_low, e.tail_high, float(np.hypot(e.tail_low, e.tail_high)))
    b_min, b_max, b_range = (
        gain * float(np.hypot(b, k * tau)) for b, k, tau in zip((b_min, b_max, b_range), gains, tails, strict=True)
    )
    return b_min, b_max, b_range


def _interval(centre: float, sd: float, floor: float | None = None) -> list[float]:
    lo, hi = centre - Z95 * sd, centre + Z95 * sd
    if floor is not None:
        lo = max(lo, floor)
    return [round(lo, 1), round(hi, 1)]


def _clip(interval: list[float], lo: float, hi: float) -> list[float]:
    """Returns [a, b] clipped into [lo, hi]."""
    a, b = interval
    return [min(max(a, lo), hi), max(min(b, hi), lo)]


def angle_intervals(
    t: np.ndarray,
    x: np.ndarray,
    sd: np.ndarray,
    name: str,
    *,
    yaw_deg: float,
    device: str = "kinect2",
    defining: bool = False,
) -> dict[str, list[float]] | None:
    """Returns {"min_deg": [lo, hi], "max_deg": [lo, hi], "range_deg": [lo, hi]} (95 %, degrees) of one angle.

    t: (T,) s. x: (T,) degrees, the angle as range_of_motion measures it (presmoothed). sd: (T,) degrees, its
    per-frame SD. name: the angle (for its systematic part and its domain). yaw_deg: the body's yaw to the camera,
    degrees (camera_yaw). device: the session's meta.device (DEVICE_GAIN). defining: the angle is one of the
    exercise's defining angles (its short tail, systematic). None when x or sd has no finite value, for the angles
    of NO_INTERVAL and for a range of MAX_RANGE_DEG or more.

    The intervals never leave what the angle can be: the ends of the range lie in its domain (angles.DOMAIN_DEG),
    the smallest value is at most the largest one's upper end (and the largest at least the smallest's lower
    end), and the range is at most the largest's upper end minus the smallest's lower end.
    """
    e = edges(t, x, sd, DEFINING_TAIL_PCT if defining else TAIL_PCT)
    if e is None or name in NO_INTERVAL or e.high - e.low >= MAX_RANGE_DEG:
        return None
    b_min, b_max, b_range = systematic(name, e, yaw_deg, device, defining)
    d_lo, d_hi = DOMAIN_DEG.get(name, (-np.inf, np.inf))
    sd_low, sd_high = SIGMA_GAIN * e.sd_low, SIGMA_GAIN * e.sd_high
    low = _clip(_interval(e.low, float(np.hypot(sd_low, b_min))), d_lo, d_hi)
    high = _clip(_interval(e.high, float(np.hypot(sd_high, b_max))), d_lo, d_hi)
    low[1], high[0] = min(low[1], high[1]), max(high[0], low[0])
    span = _interval(e.high - e.low, float(np.sqrt(sd_high**2 + sd_low**2 + b_range**2)), floor=0.0)
    span = _clip(span, 0.0, high[1] - low[0])
    return {key: [round(a, 1), round(b, 1)] for key, (a, b) in zip(KINDS, (low, high, span), strict=True)}


def withheld_reason(
    name: str, x: np.ndarray, interval: dict[str, list[float]] | None, tracked_fraction: float = 1.0
) -> Reason | None:
    """Returns why the 95 % intervals of angle `name` are not shown (a Reason of kinect_agent.analysis.reasons), or
    None when they are shown.

    x: (T,) degrees, the measured angle (NaN where undefined). interval: angle_intervals' answer. tracked_fraction:
    the fraction of the angle's joint samples the camera tracked (quality.angle_joints). Withheld: the angles of
    NO_INTERVAL, an angle defined in under MIN_DEFINED_FRACTION of the frames (its limb left its plane), one whose
    joints were tracked in under MIN_TRACKED_FRACTION of the samples, and an interval wider than MAX_WIDTH_DEG.
    """
    if name in NO_INTERVAL:
        return why.ROTATION_UNDEFINED.reason()
    x = np.asarray(x, dtype=np.float64)
    defined = float(np.isfinite(x).mean()) if x.size else 0.0
    if defined < MIN_DEFINED_FRACTION:
        return why.OUT_OF_PLANE.reason(defined=defined)
    if tracked_fraction < MIN_TRACKED_FRACTION:
        return why.JOINTS_UNTRACKED.reason(tracked=tracked_fraction)
    if interval is None:
        return why.UNKNOWN_ANGLE.reason()
    widest = max(b - a for a, b in interval.values())
    if widest > MAX_WIDTH_DEG:
        return why.TOO_UNCERTAIN.reason(width=widest, most=MAX_WIDTH_DEG)
    return None


def beyond_raw(rom: dict[str, float | None], raw: np.ndarray) -> float:
    """Returns how far (degrees, ≥ 0) a range of motion {"min_deg", "max_deg", ...} of the filtered angle leaves
    the raw angle's envelope: raw's RAW_ENVELOPE_PCT percentiles widened by RAW_MARGIN_DEG on each side. raw: (T,)
    degrees, the angle of the raw recording (NaN where undefined). 0 when inside, or when either is unknown."""
    raw = np.asarray(raw, dtype=np.float64)
    raw = raw[np.isfinite(raw)]
    lo, hi = rom.get("min_deg"), rom.get("max_deg")
    if not raw.size or lo is None or hi is None:
        return 0.0
    low, high = np.percentile(raw, RAW_ENVELOPE_PCT) + np.array([-RAW_MARGIN_DEG, RAW_MARGIN_DEG])
    return float(max(0.0, low - lo, hi - high))


def beyond_anatomy(name: str, rom: dict[str, float | None]) -> Reason | None:
    """Returns the reason beyond_anatomy when the range of motion {"max_deg", ...} of angle `name` passes its
    anatomy.FLEXION_LIMIT_DEG, else None (also for an angle without a limit or an unknown range)."""
    return limit_reason(name, rom.get("max_deg"))


def beyond_raw_reason(off: float) -> Reason:
    """Returns the reason beyond_raw of a range off (degrees, > 0) beyond the raw envelope, rounded up to 0.1° so
    that it never reads 0°."""
    return why.BEYOND_RAW.reason(by=math.ceil(round(off * 10.0, 6)) / 10.0)


def covers(interval: list[float], true: float, kind: str) -> bool:
    """True when a 95 % interval [lo, hi] (rounded to 0.1°) of metric `kind` ("min_deg", "max_deg", "range_deg")
    holds the value `true`; the ends of a range are angles, compared modulo a turn."""
    lo, hi = interval
    if kind == "range_deg":
        return lo - 0.05 <= true <= hi + 0.05
    off = (0.5 * (lo + hi) - true + 180.0) % 360.0 - 180.0
    return abs(off) <= 0.5 * (hi - lo) + 0.05


@dataclass(frozen=True)
class RomIntervals:
    """The 95 % intervals of every angle's range of motion: shown ({angle: {"min_deg", "max_deg", "range_deg":
    [lo, hi]}} or None when withheld) and, for each withheld one, why (withheld_reason)."""

    intervals: dict[str, dict[str, list[float]] | None]
    withheld: dict[str, Reason]


def rom_intervals(
    t: np.ndarray,
    angles: dict[str, np.ndarray],
    sd: dict[str, np.ndarray],
    positions: np.ndarray,
    device: str = "kinect2",
    tracked: dict[str, float] | None = None,
    defining: tuple[str, ...] = (),
    beyond: dict[str, float] | None = None,
    anatomy: dict[str, Reason] | None = None,
) -> RomIntervals:
    """Returns the RomIntervals of every angle present in both angles and sd ({name: (T,) degrees}).

    positions: (T, J, 3) metres, camera frame, the positions the angles were measured on (for camera_yaw; a
    session without both shoulders in any frame is taken as side on, 90°, the widest intervals). device: the
    session's meta.device. tracked: {angle: fraction of its joint samples tracked} (1 when not given). defining:
    the exercise's defining angles (angle_intervals' `defining`). beyond: {angle: degrees its range of motion leaves
    the raw angle's envelope (beyond_raw)}; an angle beyond it by more than 0 has its intervals withheld for that
    reason before any other (its range is withheld too). anatomy: {angle: beyond_anatomy reason} of ranges past
    what the joint bends, withheld for that reason first.
    """
    yaw = camera_yaw(positions)
    yaw = 90.0 if yaw is None else yaw
    shown: dict[str, dict[str, list[float]] | None] = {}
    withheld: dict[str, Reason] = {}
    for name in angles:
        if name not in sd:
            continue
        iv = angle_intervals(t, angles[name], sd[name], name, yaw_deg=yaw, device=device, defining=name in defining)
        off = (beyond or {}).get(name, 0.0)
        # a range beyond the raw data is itself withheld (report.analyze_recording): its interval says the same
        reason = (anatomy or {}).get(name) or (beyond_raw_reason(off) if off > 0.0 else withheld_reason(
            name, angles[name], iv, (tracked or {}).get(name, 1.0)))  # fmt: skip
        shown[name] = None if reason else iv
        if reason:
            withheld[name] = reason
    return RomIntervals(shown, withheld)


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
    count: int | None = None,
) -> CountInterval:
    """Returns the repetition count's interval: the counts of n_draws perturbed copies of the defining angles.

    angles: {name: (T,) degrees} as count_repetitions takes them; sd: {name: (T,) degrees} their per-frame SDs
    (a name without one is not perturbed). The interval always holds the count of the unperturbed angles: `count`
    when the caller has it (count_repetitions of the same angles and params), else counted here.
    """
    t = np.asarray(t, dtype=np.float64)
    rng = np.random.default_rng(seed)
    counts = [len(count_repetitions(t, angles, names, params).repetitions) if count is None else count]
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


__all__ = [
    "SYSTEMATIC_DEG",
    "CountInterval",
    "Edges",
    "RomIntervals",
    "angle_intervals",
    "beyond_anatomy",
    "beyond_raw_reason",
    "count_interval",
    "edges",
    "rom_intervals",
    "withheld_reason",
]
