"""Moving time, tempo and fatigue."""

from __future__ import annotations

import numpy as np

from kinect_agent.analysis import activity, series
from kinect_agent.analysis.repetitions import Repetition
from kinect_agent.skeleton import INDEX, J
from kinect_agent.sources.simulator import simulate_truth


def _rep(i: int, start: float, duration: float, amplitude: float) -> Repetition:
    return Repetition(i, start, start + duration, duration, amplitude, amplitude, "left")


def test_moving_time_of_a_move_then_rest() -> None:
    t = np.arange(600) / 30.0  # 20 s
    p = np.zeros((600, J, 3))
    moving = t < 8.0
    p[:, INDEX["HAN_L"], 1] = np.where(moving, 0.3 * np.sin(2 * np.pi * t / 2.0), 0.0)  # ~0.9 m/s peak
    moving_s, rest_s = activity.moving_time(t, series.smooth_positions(t, p))
    assert abs(moving_s - 8.0) < 1.0 and abs(moving_s + rest_s - t[-1]) < 0.02


def test_simulated_session_moves_about_two_thirds_of_the_time() -> None:
    truth = simulate_truth("squat", 6, seed=2)
    moving_s, rest_s = activity.moving_time(truth.t, series.smooth_positions(truth.t, truth.positions))
    assert 0.4 < moving_s / truth.duration < 0.9 and rest_s > 0


def test_tempo_is_the_median_start_interval() -> None:
    reps = [_rep(i, s, 2.0, 90.0) for i, s in enumerate([0.0, 3.0, 6.5, 9.5])]
    assert activity.tempo(reps) == 3.0
    assert activity.tempo(reps[:1]) == 2.0
    assert activity.tempo([]) is None


def test_fatigue_slopes_in_percent_per_repetition() -> None:
    reps = [_rep(i, 3.0 * i, 2.0 + 0.1 * i, 100.0 - 2.0 * i) for i in range(5)]
    f = activity.fatigue(reps)
    assert f["amplitude_slope_pct_per_rep"] is not None and f["duration_slope_pct_per_rep"] is not None, f
    np.testing.assert_allclose(f["amplitude_slope_pct_per_rep"], -2.0 / 96.0 * 100, atol=0.01)
    np.testing.assert_allclose(f["duration_slope_pct_per_rep"], 0.1 / 2.2 * 100, atol=0.01)
    assert activity.fatigue(reps[:2]) == {"amplitude_slope_pct_per_rep": None, "duration_slope_pct_per_rep": None}
