"""The interval arithmetic of backend.analysis.intervals on simple series, and the repetition count's interval."""

from __future__ import annotations

import numpy as np
import pytest

from backend.analysis import intervals
from backend.exercises.library import EXERCISES
from kinect_agent.analysis import series
from kinect_agent.analysis.angles import counting_angles
from kinect_agent.processing.angles import joint_angles
from kinect_agent.processing.pipeline import process
from kinect_agent.sources.simulator import simulate

SEEDS = (1, 2, 3)


def _sine(seed: int) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(600) / 30.0
    rng = np.random.default_rng(seed)
    return t, 60.0 + 40.0 * np.sin(2 * np.pi * t / 4.0 + rng.uniform(0, 6))


@pytest.mark.parametrize("seed", SEEDS)
def test_widths_follow_the_per_frame_sd_and_the_systematic_part(seed):
    t, x = _sine(seed)
    sd = np.full_like(t, 2.0)
    iv = intervals.angle_intervals(t, x, sd, "trunk_flexion")  # b = (0, 2.6, 0)
    lo, hi = np.percentile(x, [1, 99])
    np.testing.assert_allclose(np.mean(iv["min_deg"]), lo, atol=0.1, err_msg=f"seed {seed}")
    np.testing.assert_allclose(np.diff(iv["min_deg"])[0], 2 * 1.96 * 2.0, atol=0.2, err_msg=f"seed {seed}")
    np.testing.assert_allclose(np.diff(iv["max_deg"])[0], 2 * 1.96 * np.hypot(2.0, 2.6), atol=0.2)
    np.testing.assert_allclose(np.diff(iv["range_deg"])[0], 2 * 1.96 * np.sqrt(8.0), atol=0.2)


def test_no_interval_for_shoulder_rotation_or_a_spinning_angle():
    t, x = _sine(1)
    sd = np.ones_like(t)
    assert intervals.angle_intervals(t, x, sd, "shoulder_rotation_L") is None
    assert intervals.angle_intervals(t, np.linspace(0, 720, t.size), sd, "elbow_flexion_L") is None
    assert intervals.angle_intervals(t, np.full_like(t, np.nan), sd, "elbow_flexion_L") is None


def test_a_range_never_goes_below_zero():
    t = np.arange(300) / 30.0
    iv = intervals.angle_intervals(t, np.full_like(t, 10.0), np.full_like(t, 5.0), "elbow_flexion_L")
    assert iv["range_deg"][0] == 0.0


def test_shapes_are_checked():
    t, x = _sine(1)
    with pytest.raises(ValueError, match="shape"):
        intervals.angle_intervals(t, x[:-1], np.ones_like(t), "elbow_flexion_L")


def test_covers_compares_the_ends_of_a_range_modulo_a_turn():
    assert intervals.covers([170.0, 190.0], -175.0, "max_deg")
    assert not intervals.covers([170.0, 190.0], -175.0, "range_deg")
    assert intervals.covers([0.0, 10.0], 10.0, "range_deg")


@pytest.mark.parametrize("seed", SEEDS)
def test_the_count_interval_holds_the_true_count_of_a_clean_session(seed):
    measured, _, _ = simulate("elbow_flexion", 6, seed=seed)
    result = process(measured)
    names = EXERCISES["elbow_flexion"].defining_angles
    smoothed = series.smooth_positions(measured.t, result.filtered.positions)
    angles = counting_angles(smoothed, names, joint_angles(smoothed))
    ci = intervals.count_interval(measured.t, angles, result.angle_sd, names)
    assert ci.low <= 6 <= ci.high, f"seed {seed}: {ci}"
    assert ci.high - ci.low <= 2, f"seed {seed}: {ci}"
    assert ci.to_dict()["ambiguous"] == (ci.low != ci.high)
