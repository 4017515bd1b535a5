"""Sit-to-stand rise times from the hip height."""

from __future__ import annotations

import numpy as np

from kinect_agent.analysis.sit_to_stand import rise_times, sit_to_stand
from kinect_agent.sources.simulator import simulate_truth


def test_linear_rises_have_known_20_80_times() -> None:
    t = np.arange(0, 20, 1 / 30)
    cycle = np.clip(np.abs((t % 5.0) - 2.5) - 0.5, 0, 1.5) / 1.5  # 0 seated .. 1 standing, 1.5 s rise
    times = rise_times(t, 0.4 * (1 - cycle))  # hip 0.4 m higher when standing; starts standing
    assert len(times) == 4
    np.testing.assert_allclose(times, 0.6 * 1.5, atol=2 / 30)


def test_simulated_sit_to_stand_counts_every_rise() -> None:
    truth = simulate_truth("sit_to_stand", 5, seed=3)
    result = sit_to_stand(truth.t, truth.positions)
    assert result is not None
    assert result["count"] == 5 and 0.2 < result["mean_s"] < 2.0


def test_standing_exercise_has_no_transition() -> None:
    truth = simulate_truth("shoulder_abduction", 3, seed=1)
    assert sit_to_stand(truth.t, truth.positions) is None
