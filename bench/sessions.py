"""The long recordings the speed and ingest benchmarks time: simulated squats back to back, clean or outlier-heavy."""

from __future__ import annotations

import numpy as np

from kinect_agent import skeleton
from kinect_agent.recording import Recording
from kinect_agent.sources.simulator import simulate

HARD_FRACTION = 0.10  # joint-frames lost or wild in the outlier-heavy session (issue 24 point 5: "about 10 %")
HARD_BURST_S = (0.03, 0.5)  # shortest and longest tracking-loss burst, s
HARD_WILD_M = (0.3, 1.5)  # a wild joint lands this far from where the Kinect put it, m


def squat_session(minutes: float, seed: int = 1) -> Recording:
    """Returns a simulated Kinect 2 recording (30° view, standing) of `minutes` minutes at 30 Hz: sets of 10 squats
    back to back, cut at `minutes` (at least 2 frames), meta.exercise = "squat"."""
    parts: list[Recording] = []
    total = 0.0
    while total < minutes * 60.0:
        measured, _, _ = simulate("squat", 10, device="kinect2", view_deg=30, pose="standing", seed=seed + len(parts))
        parts.append(measured)
        total += measured.duration
    rec = Recording.concatenate(parts)
    rec = rec.slice(0, max(int(np.searchsorted(rec.t, minutes * 60.0)), 2))
    rec.meta.exercise = "squat"
    return rec


def _burst_mask(rng: np.random.Generator, T: int, fraction: float, rate_hz: float) -> np.ndarray:
    """Returns (T, J) bool: per joint, bursts of uniform length in HARD_BURST_S at random starts until `fraction`
    of the joint's frames are covered (bursts may overlap; the cover is exact to one burst)."""
    lo, hi = (max(1, int(round(s * rate_hz))) for s in HARD_BURST_S)
    mask = np.zeros((T, skeleton.J), dtype=bool)
    for j in range(skeleton.J):
        while mask[:, j].mean() < fraction:
            start, length = int(rng.integers(0, T)), int(rng.integers(lo, hi + 1))
            mask[start : start + length, j] = True
    return mask


def outlier_heavy_session(minutes: float, seed: int = 1, fraction: float = HARD_FRACTION) -> Recording:
    """Returns squat_session(minutes, seed) with tracking loss added until about `fraction` of its joint-frames are
    lost or wild: per joint, bursts of 1-15 frames; half of the bursts lose the joint (NaN, state 0), the others
    throw it HARD_WILD_M away in a random direction drawn once per burst frame (state kept TRACKED, as the Kinect SDK
    often does). Deterministic in seed. positions: (T, J, 3) m, camera frame."""
    rec = squat_session(minutes, seed)
    rng = np.random.default_rng([seed, 24, 5])
    T, rate = rec.n_frames, rec.rate_hz
    already = (rec.state == skeleton.NOT_TRACKED).mean()
    hit = _burst_mask(rng, T, max(fraction - already, 0.0), rate)
    # Lose or throw: one choice per burst (bursts numbered by their starts down each joint's column).
    starts = hit & ~np.vstack([np.zeros((1, skeleton.J), bool), hit[:-1]])
    burst_id = np.cumsum(starts, axis=0)
    lost_bursts = rng.random(int(burst_id.max()) + 1) < 0.5
    lose = hit & lost_bursts[burst_id]
    wild = hit & ~lose
    direction = rng.standard_normal((T, skeleton.J, 3))
    direction /= np.linalg.norm(direction, axis=-1, keepdims=True)
    distance = rng.uniform(*HARD_WILD_M, size=(T, skeleton.J, 1))
    base = np.where(np.isfinite(rec.positions), rec.positions, np.nanmedian(rec.positions, axis=0))
    positions = np.where(wild[..., None], base + distance * direction, rec.positions)
    positions[lose] = np.nan
    state = np.where(lose, skeleton.NOT_TRACKED, np.where(wild, skeleton.TRACKED, rec.state)).astype(np.int8)
    out = rec.replace(step=f"outlier-heavy: {fraction:.0%} of joint-frames lost or wild (seed {seed})",
                      positions=positions, state=state)  # fmt: skip
    out.meta.exercise = rec.meta.exercise
    return out
