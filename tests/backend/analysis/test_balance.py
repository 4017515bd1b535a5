"""Body-centre sway while standing still."""

from __future__ import annotations

import numpy as np

from backend.analysis.balance import CHI2_95_2DOF, sway
from kinect_agent.analysis import series
from kinect_agent.body.angles import joint_angles
from kinect_agent.skeleton import INDEX
from kinect_agent.sources.simulator import simulate_truth


def _still_body(n: int) -> np.ndarray:
    return np.repeat(simulate_truth("elbow_flexion", 1, seed=1, pose="standing").positions[:1], n, axis=0)


def test_circular_sway_path_and_area() -> None:
    t = np.arange(900) / 30.0  # 30 s
    p = _still_body(900)
    r = 0.01  # the body centre circles with a 1 cm radius every 10 s
    shift = np.stack([r * np.cos(2 * np.pi * t / 10), np.zeros_like(t), r * np.sin(2 * np.pi * t / 10)], axis=1)
    p[:, [INDEX["ROOT"], INDEX["SPINE"]]] += shift[:, None, :]
    b = sway(t, p, joint_angles(p))
    np.testing.assert_allclose(b["sway_path_m"], 3 * 2 * np.pi * r, rtol=0.02)
    # a uniform circle of radius r has covariance r²/2 per axis
    np.testing.assert_allclose(b["sway_area_m2"], np.pi * CHI2_95_2DOF * r**2 / 2, rtol=0.05)
    np.testing.assert_allclose(b["standing_s"], t[-1], atol=0.05)


def test_sitting_has_no_balance() -> None:
    truth = simulate_truth("elbow_flexion", 3, seed=1, pose="sitting")
    assert sway(truth.t, series.smooth_positions(truth.t, truth.positions), joint_angles(truth.positions)) is None


def test_squatting_counts_only_the_still_standing_frames() -> None:
    truth = simulate_truth("squat", 4, seed=1)
    b = sway(truth.t, series.smooth_positions(truth.t, truth.positions), joint_angles(truth.positions))
    assert b is not None and b["standing_s"] < 0.6 * truth.duration
    assert b["sway_velocity_m_s"] < 0.05
