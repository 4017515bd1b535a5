"""Most-moving joints: ranking by path length."""

from __future__ import annotations

import numpy as np

from kinect_agent.analysis import series
from kinect_agent.analysis.most_moving import most_moving_joints, path_lengths
from kinect_agent.skeleton import INDEX, J
from kinect_agent.sources.simulator import simulate_truth


def test_path_of_a_joint_moving_on_a_circle() -> None:
    t = np.arange(301) / 30.0
    p = np.zeros((301, J, 3))
    angle = 2 * np.pi * t / 10.0  # one turn of radius 0.5 m in 10 s
    p[:, INDEX["HAN_L"], 0] = 0.5 * np.cos(angle)
    p[:, INDEX["HAN_L"], 1] = 0.5 * np.sin(angle)
    lengths = path_lengths(p)
    np.testing.assert_allclose(lengths[INDEX["HAN_L"]], 2 * np.pi * 0.5, rtol=1e-3)
    assert most_moving_joints(p)[0] == {"joint": "HAN_L", "path_m": round(float(lengths[INDEX["HAN_L"]]), 3)}


def test_elbow_exercise_ranks_hands_and_wrists_first() -> None:
    truth = simulate_truth("elbow_flexion", 4, seed=1)
    ranked = most_moving_joints(series.smooth_positions(truth.t, truth.positions))
    assert len(ranked) == J
    assert {r["joint"] for r in ranked[:4]} == {"HAN_L", "HAN_R", "WRI_L", "WRI_R"}
    assert all(a["path_m"] >= b["path_m"] for a, b in zip(ranked, ranked[1:], strict=False))


def test_smoothing_keeps_jitter_from_adding_path(rng: np.random.Generator) -> None:
    t = np.arange(600) / 30.0
    p = np.zeros((600, J, 3)) + rng.normal(0, 0.01, (600, J, 3))  # standing still, 1 cm jitter
    raw = path_lengths(p).mean()
    smoothed = path_lengths(series.smooth_positions(t, p)).mean()
    assert smoothed < 0.2 * raw
