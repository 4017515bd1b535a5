"""Test data for the signal pipeline: smooth synthetic motion through the chain, and short real Kinect clips."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from kinect_agent import formats, skeleton
from kinect_agent.body import kinematics as km
from kinect_agent.processing.ik import R_FACING
from kinect_agent.recording import Metadata, Recording


def smooth_motion(
    frames: int, rng: np.random.Generator, rate_hz: float = 30.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Returns (t (T,) s, positions (T, J, 3) m, lengths (19,) m): sinusoidal joint angles of a subject facing a
    camera 2.5 m away; elbows bend forward and knees backward, as anatomy allows."""
    t = np.arange(frames) / rate_hz
    freq = rng.uniform(0.2, 0.8, km.N_THETA)
    amp = rng.uniform(0.05, 0.4, km.N_THETA)
    phase = rng.uniform(0.0, 2 * np.pi, km.N_THETA)
    theta = amp * np.sin(2 * np.pi * freq * t[:, None] + phase)
    for r in km.ROT_1DOF:
        name = skeleton.JOINTS[km.ROT_JOINTS[r]]
        bend = 0.1 + 0.5 * rng.uniform(0.3, 1.2) * (1 - np.cos(2 * np.pi * rng.uniform(0.2, 0.5) * t))
        theta[:, km.ROT_START[r]] = -bend if name.startswith("ELB") else bend
    model = km.ChainModel()
    model.R_ref[0] = R_FACING
    root = np.stack([0.1 * np.sin(0.5 * t), 0.9 + 0.05 * np.sin(1.1 * t), 2.5 + 0.05 * np.cos(0.3 * t)], axis=-1)
    lengths = km.TYPICAL_LENGTHS * rng.uniform(0.9, 1.1, km.N_BONES)
    return t, model.positions(root, np.broadcast_to(lengths, (frames, km.N_BONES)), theta), lengths


def inject_outliers(
    rec: Recording, rng: np.random.Generator, rate: float = 0.03, burst: tuple[int, int] = (1, 4)
) -> tuple[Recording, np.ndarray]:
    """Returns (recording with tracking-loss outliers, mask (T, J) bool): bursts of 1-4 frames in which a joint is
    placed uniformly in the box around the body grown by 0.5 m; about `rate` of all joint-frames."""
    T = rec.n_frames
    mask = np.zeros((T, skeleton.J), dtype=bool)
    for _ in range(int(rate * T * skeleton.J / np.mean(burst))):
        j, k, n = rng.integers(skeleton.J), rng.integers(T), rng.integers(burst[0], burst[1] + 1)
        mask[k : k + n, j] = True
    mask &= rec.state != skeleton.NOT_TRACKED
    lo = np.nanmin(rec.positions.reshape(-1, 3), axis=0) - 0.5
    hi = np.nanmax(rec.positions.reshape(-1, 3), axis=0) + 0.5
    positions = rec.positions.copy()
    positions[mask] = rng.uniform(lo, hi, (int(mask.sum()), 3))
    return rec.replace(step="test: outliers injected", positions=positions), mask


def utkinect(data_dir: Path, name: str = "joints_s01_e01.txt", frames: int = 240) -> Recording:
    """Returns the first `frames` frames of a UTKinect-Action3D file (Kinect v1, SDK joint order = ours, 30 Hz).

    Read by the project's reader when it exists; otherwise parsed here (frame id + 20 × xyz, duplicate ids dropped).
    """
    path = data_dir / "utkinect" / name
    if "utkinect" in formats.available():
        return formats.read(path, "utkinect").slice(0, frames)
    raw = np.loadtxt(path)
    _, first = np.unique(raw[:, 0], return_index=True)
    raw = raw[np.sort(first)][:frames]
    return Recording.from_positions(
        raw[:, 0] / 30.0, raw[:, 1:].reshape(-1, skeleton.J, 3), Metadata(device="kinect1", rate_hz=30.0)
    )
