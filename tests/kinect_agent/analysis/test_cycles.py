"""The cycle of a repeated movement: period from the autocorrelation, amplitude robust to a spike, drifting rest."""

from __future__ import annotations

import numpy as np
import pytest

from kinect_agent.analysis import cycles
from kinect_agent.analysis.repetitions import count_repetitions

SEEDS = (0, 1, 2)


def _bumps(t: np.ndarray, period_s: float, heights: np.ndarray, width_s: float = 1.0) -> np.ndarray:
    """Returns (T,) degrees: one raised-cosine excursion of width_s per period, heights (N,) degrees."""
    e = np.zeros_like(t)
    for k, h in enumerate(heights):
        u = (t - (k + 0.5) * period_s) / width_s
        inside = np.abs(u) < 0.5
        e[inside] += h * 0.5 * (1 + np.cos(2 * np.pi * u[inside]))
    return e


@pytest.mark.parametrize("seed", SEEDS)
def test_period_and_amplitude_of_a_noisy_repeated_movement(seed: int) -> None:
    rng = np.random.default_rng(seed)
    period = rng.uniform(1.8, 3.0)
    t = np.arange(0, 10 * period, 1 / 30)
    heights = rng.uniform(60, 100, 10)
    e = _bumps(t, period, heights) + rng.normal(0, 1.5, t.shape)
    cyc = cycles.cycle(t, np.clip(e, 0, None))
    assert cyc.period_s == pytest.approx(period, rel=0.05)
    assert cyc.n_cycles == 10
    assert cyc.amplitude_deg == pytest.approx(np.median(heights), rel=0.1)


@pytest.mark.parametrize("seed", SEEDS)
def test_one_spike_does_not_move_the_amplitude(seed: int) -> None:
    """A mistracked frame run at 3x the height: the range follows it, the cycle amplitude hardly does."""
    rng = np.random.default_rng(seed)
    t = np.arange(0, 25, 1 / 30)
    heights = rng.uniform(40, 60, 10)
    heights[rng.integers(10)] = 170.0
    e = _bumps(t, 2.5, heights)
    assert cycles.cycle(t, e).amplitude_deg < 1.2 * np.median(heights)


def test_no_period_in_one_movement() -> None:
    t = np.arange(0, 10, 1 / 30)
    e = _bumps(t, 10.0, np.array([90.0]), width_s=3.0)
    cyc = cycles.cycle(t, e)
    assert cyc.period_s is None and cyc.amplitude_deg == pytest.approx(90.0, rel=0.02)


@pytest.mark.parametrize("seed", SEEDS)
def test_small_repetitions_on_a_drifting_rest_are_all_counted(seed: int) -> None:
    """Ten repetitions whose rest level drifts by 30° over the set and three of which are under half the others,
    with one mistracked excursion at twice the others' height: all ten count."""
    rng = np.random.default_rng(seed)
    t = np.arange(0, 25, 1 / 30)
    heights = rng.uniform(50, 70, 10)
    heights[rng.choice(9, 3, replace=False) + 1] = rng.uniform(26, 30, 3)
    heights[0] = 130.0
    x = 30 * t / t[-1] + _bumps(t, 2.5, heights, width_s=1.6) + rng.normal(0, 1.0, t.shape)
    reps = count_repetitions(t, {"elbow_flexion_L": x}, ("elbow_flexion_L",)).repetitions
    assert len(reps) == 10, [round(r.amplitude_deg) for r in reps]
