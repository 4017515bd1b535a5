"""The long recording the speed and ingest benchmarks time: simulated squats back to back."""

from __future__ import annotations

import numpy as np

from kinect_agent.recording import Recording
from kinect_agent.sources.simulator import simulate


def squat_session(minutes: float, seed: int = 1) -> Recording:
    """Returns a simulated Kinect 2 recording (30° view, standing) of `minutes` minutes at 30 Hz: sets of 10 squats
    back to back, cut at `minutes` (at least 2 frames), meta.exercise = "squat"."""
    parts, total = [], 0.0
    while total < minutes * 60.0:
        measured, _, _ = simulate("squat", 10, device="kinect2", view_deg=30, pose="standing", seed=seed + len(parts))
        parts.append(measured)
        total += measured.duration
    rec = Recording.concatenate(parts)
    rec = rec.slice(0, max(int(np.searchsorted(rec.t, minutes * 60.0)), 2))
    rec.meta.exercise = "squat"
    return rec
