"""Quality of a session: tracked and outlier fractions and the ok flag."""

from __future__ import annotations

import numpy as np

from kinect_agent.analysis.quality import angle_joints, assess
from kinect_agent.recording import Recording
from kinect_agent.skeleton import INDEX
from kinect_agent.sources.simulator import simulate_truth


def test_clean_recording_is_ok() -> None:
    truth = simulate_truth("elbow_flexion", 2, seed=1)
    q = assess(truth, truth.positions, ("elbow_flexion_L",))
    assert q == {"ok": True, "tracked_fraction": 1.0, "outlier_fraction": 0.0, "reasons": []}


def test_outliers_are_samples_far_from_the_measured_positions(rng: np.random.Generator) -> None:
    truth = simulate_truth("elbow_flexion", 2, seed=1)
    raw = truth.positions.copy()
    frames = rng.choice(truth.n_frames, truth.n_frames // 5, replace=False)
    raw[frames, INDEX["WRI_L"]] += 0.5  # a fifth of the left wrist samples thrown 0.5 m away
    q = assess(Recording.from_positions(truth.t, raw, truth.meta), truth.positions, ("elbow_flexion_L",))
    n_joints = len(angle_joints(("elbow_flexion_L",)))
    np.testing.assert_allclose(q["outlier_fraction"], 0.2 / n_joints, atol=2e-3)


def test_too_short_recording_is_not_ok() -> None:
    truth = simulate_truth("elbow_flexion", 1, seed=1).slice(0, 20)
    q = assess(truth, None, ())
    assert q["ok"] is False and [r.id for r in q["reasons"]] == ["too_few_frames", "too_short"]


def test_angle_joints_of_a_knee_angle() -> None:
    names = {i for i in angle_joints(("knee_flexion_R",))}
    assert {INDEX["HIP_R"], INDEX["KNE_R"], INDEX["ANK_R"], INDEX["ROOT"]} <= names
    assert INDEX["ANK_L"] not in names
