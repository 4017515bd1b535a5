"""A simulated Kinect/mocap pair with a known time offset: the simulator's exact motion at 120 Hz as the mocap,
and the calibrated Kinect errors (kinect_noise) added to that motion resampled at 30 Hz, shifted in time."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from kinect_agent import formats, skeleton
from kinect_agent.evaluation.align import interpolate
from kinect_agent.recording import Recording
from kinect_agent.sources.kinect_noise import add_kinect_noise
from kinect_agent.sources.simulator import simulate_truth

KINECT_HZ, MOCAP_HZ = 30.0, 120.0


def simulated_pair(seed: int, lag_s: float, *, device: str = "kinect2", pose: str = "standing",
                   exercise: str = "squat", reps: int = 12) -> tuple[Recording, Recording, np.ndarray]:  # fmt: skip
    """Returns (kinect 30 Hz, mocap 120 Hz, outlier mask (T, J)) with mocap time = kinect time + lag_s.

    Both are in the Kinect camera frame. kinect.t starts at 0; mocap.t covers [0, duration].
    """
    mocap = simulate_truth(exercise, reps, pose=pose, seed=seed, rate_hz=MOCAP_HZ)
    t0 = max(0.0, -lag_s)
    T = int((mocap.t[-1] - abs(lag_s)) * KINECT_HZ) - 1
    t_k = t0 + np.arange(T) / KINECT_HZ
    exact = Recording(t_k - t0, interpolate(mocap.t, mocap.positions, t_k + lag_s),
                      np.full((T, skeleton.J), skeleton.TRACKED, np.int8),
                      dataclasses.replace(mocap.meta, rate_hz=KINECT_HZ))  # fmt: skip
    kinect, mask = add_kinect_noise(exact, device=device, view_deg=0, pose=pose, rng=np.random.default_rng([seed, 7]))
    shifted = Recording(mocap.t + t0, mocap.positions, mocap.state, mocap.meta)
    return kinect, shifted, mask


def write_pair(folder: Path, name: str, kinect: Recording, mocap: Recording) -> tuple[Path, Path]:
    """Writes the pair as skeleton CSV files NAME_kinect.csv and NAME_mocap.csv; returns their paths."""
    k, m = folder / f"{name}_kinect.csv", folder / f"{name}_mocap.csv"
    formats.write(kinect, k)
    formats.write(mocap, m)
    return k, m
