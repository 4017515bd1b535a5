"""How much measurement noise a recording shows in its own segment lengths, and whether it is a rigid (exact) input.

A body's segments have constant lengths, so the spread of each measured segment length over the frames is noise.
Independent noise of SD σ per axis on both ends of a segment spreads its length by σ·√2; the estimate is the median
over the 14 segments of the robust SD (1.4826 · median absolute deviation) of the length, divided by √2.

What it separates (bench/README.md, "Fed the truth, return the truth"): motion capture and any recording rebuilt
from a rigid skeleton (the simulator's truth, an already filtered recording) show < 0.2 mm; white noise of SD σ
shows ≈ σ; real Kinect recordings 1.1-24 mm (the lowest: UI-PRMD's deep squats and sit-to-stands), although their
error against mocap is 40-80 mm: Kinect's error is slow and common to neighbouring joints, which a length does not
see. So the estimate cannot set a Kinect recording's measurement SD, but it does tell an exact input from a
Kinect's: below PipelineConfig.rigid_input_sd_m the offline filter takes the input as exact up to the chain's own
misfit (rigid_settings).
"""

from __future__ import annotations

import numpy as np

from kinect_agent import skeleton
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.recording import Recording
from kinect_agent.skeleton import NOT_TRACKED

MIN_FRAMES = 10  # a segment counts with at least this many frames with both ends tracked
MIN_SEGMENTS = 3  # fewer segments than this: no estimate


def segment_noise_m(rec: Recording) -> float | None:
    """Returns the recording's measurement SD per axis estimated from its segment lengths, m (None: fewer than
    MIN_SEGMENTS segments have MIN_FRAMES frames with both ends tracked)."""
    positions = np.where((rec.state != NOT_TRACKED)[..., None], rec.positions, np.nan)
    lengths = skeleton.segment_lengths(positions)  # (T, 14), NaN where an end is missing
    spreads = []
    for column in lengths.T:
        present = column[np.isfinite(column)]
        if len(present) >= MIN_FRAMES:
            spreads.append(1.4826 * float(np.median(np.abs(present - np.median(present)))))
    if len(spreads) < MIN_SEGMENTS:
        return None
    return float(np.median(spreads)) / float(np.sqrt(2.0))


def is_rigid(noise_m: float | None, config: PipelineConfig) -> bool:
    """Returns whether a recording with segment noise `noise_m` (m, segment_noise_m) is taken as exact."""
    return config.rigid_input_sd_m is not None and noise_m is not None and noise_m < config.rigid_input_sd_m


def rigid_settings(config: PipelineConfig) -> PipelineConfig:
    """Returns the offline settings for an exact input: the measurement SD of the chain's own misfit
    (rigid_input_sigma_m), the innovation at the mean state's joints in every pass (no unscented-mean stretch), and an
    outlier that must also break its bones (outlier_segment "and": a clean recording's fastest frames are no outliers),
    and no device length bias (an exact input's bones are the body's).
    """
    ratio = config.rigid_input_sigma_m / config.sigma_tracked_m  # inferred joints keep their ratio to tracked ones
    return config.model_copy(
        update={
            "sigma_tracked_m": config.rigid_input_sigma_m,
            "sigma_inferred_m": config.sigma_inferred_m * ratio,
            "innovation_at_mean": True,
            "fixed_innovation_at_mean": True,
            "outlier_segment": "and",
            "length_bias": None,
        }
    )


__all__ = ["MIN_FRAMES", "MIN_SEGMENTS", "is_rigid", "rigid_settings", "segment_noise_m"]
