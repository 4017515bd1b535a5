"""Simulated webcam sets: the simulator's exact motion with the errors measured on a monocular landmarker
(bench/README.md, "Webcam"): jitter 10 mm across the image and 25 mm in depth per joint, the fitted hip distance
jittering 30 mm for the whole body, and, with swaps, a sixth of the set where the labels of left and right flicker
(the side view's swaps). Used by the webcam filter's tests and bench/webcam_counts.py."""

from __future__ import annotations

import numpy as np

from kinect_agent.processing.label_swaps import MIRROR
from kinect_agent.recording import Metadata, Recording


def webcam_like(truth: Recording, seed: int, swaps: bool = True) -> Recording:
    """Returns the truth (device webcam, the truth's exercise) with the webcam's measured errors (module docstring)."""
    rng = np.random.default_rng(seed)
    T = truth.n_frames
    pos = truth.positions + rng.normal(0.0, 1.0, truth.positions.shape) * np.array([0.01, 0.01, 0.025])
    pos[..., 2] += rng.normal(0.0, 0.03, (T, 1))
    if swaps:
        stretch = np.arange(T // 3, T // 3 + T // 6)
        flicker = stretch[rng.random(stretch.size) < 0.5]
        pos[flicker] = pos[flicker][:, MIRROR]
    meta = Metadata(device="webcam", rate_hz=truth.meta.rate_hz, exercise=truth.meta.exercise)
    return Recording(truth.t.copy(), pos, truth.state.copy(), meta)
