"""Simulated webcam sets: the simulator's exact motion with the errors measured on a monocular landmarker
(bench/README.md, "Webcam"): jitter 10 mm across the image and 25 mm in depth per joint, the fitted hip distance
jittering 30 mm for the whole body, and, with swaps, a sixth of the set where the labels of left and right flicker
(the side view's swaps; with arms_only, the arms' labels alone, the legs keeping theirs). With wobble_m > 0, also a
slow wobble of every joint (Gaussian noise smoothed over WOBBLE_S, SD wobble_m across the image and 2.5 x in depth):
the landmarker's angles drifting on a person standing still (a small or far person: bench/README.md, "Webcam
counts"). Used by the webcam filter's tests and bench/webcam_counts.py."""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter1d

from kinect_agent.processing.label_swaps import ARM_PAIRS, MIRROR
from kinect_agent.recording import Metadata, Recording

ARMS = np.array([j for pair in ARM_PAIRS for j in pair])  # the arms' joints, whose labels alone flicker with arms_only
WOBBLE_S = 0.25  # s, the SD of the Gaussian that makes the wobble slow (its excursions last about a second)


def wobble(t: np.ndarray, shape: tuple[int, ...], sd_m: float, seed: int) -> np.ndarray:
    """Returns (T, J, 3) m: a slow wobble of every joint coordinate at times t: (T,) s (module docstring), SD sd_m
    across the image and 2.5 x sd_m in depth."""
    rng = np.random.default_rng([seed, 7])
    sigma = WOBBLE_S * (t.shape[0] - 1) / max(float(t[-1] - t[0]), 1e-9)
    w = gaussian_filter1d(rng.normal(0.0, 1.0, shape), sigma, axis=0, mode="wrap")
    w /= w.reshape(shape[0], -1).std(axis=0).reshape(shape[1:])
    return w * sd_m * np.array([1.0, 1.0, 2.5])


def webcam_like(
    truth: Recording, seed: int, swaps: bool = True, wobble_m: float = 0.0, arms_only: bool = False
) -> Recording:
    """Returns the truth (device webcam, the truth's exercise) with the webcam's measured errors (module docstring)."""
    rng = np.random.default_rng(seed)
    T = truth.n_frames
    pos = truth.positions + rng.normal(0.0, 1.0, truth.positions.shape) * np.array([0.01, 0.01, 0.025])
    pos[..., 2] += rng.normal(0.0, 0.03, (T, 1))
    if wobble_m > 0:
        pos += wobble(truth.t, truth.positions.shape, wobble_m, seed)
    if swaps:
        stretch = np.arange(T // 3, T // 3 + T // 6)
        flicker = stretch[rng.random(stretch.size) < 0.5]
        joints = ARMS if arms_only else np.arange(pos.shape[1])
        swapped = pos[flicker]
        swapped[:, joints] = swapped[:, MIRROR[joints]]
        pos[flicker] = swapped
    meta = Metadata(device="webcam", rate_hz=truth.meta.rate_hz, exercise=truth.meta.exercise)
    return Recording(truth.t.copy(), pos, truth.state.copy(), meta)
