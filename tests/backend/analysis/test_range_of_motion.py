"""Range of motion per clinical angle: known ranges, wrapped angles, untracked angles."""

from __future__ import annotations

import numpy as np

from backend.analysis.range_of_motion import range_of_motion


def test_known_sine_range(rng: np.random.Generator) -> None:
    t = np.arange(600) / 30.0
    x = 50 + 40 * np.sin(2 * np.pi * t / 4.0) + rng.normal(0, 1.5, t.shape)
    rom = range_of_motion(t, {"elbow_flexion_L": x})["elbow_flexion_L"]
    assert abs(rom["min_deg"] - 10) < 3 and abs(rom["max_deg"] - 90) < 3 and abs(rom["range_deg"] - 80) < 5


def test_angle_wrapping_at_180_is_not_a_360_degree_range() -> None:
    t = np.arange(300) / 30.0
    x = 170 + 20 * np.sin(2 * np.pi * t / 5.0)  # crosses +180 -> reads -170..-180
    wrapped = (x + 180) % 360 - 180
    rom = range_of_motion(t, {"shoulder_abduction_L": wrapped})["shoulder_abduction_L"]
    assert abs(rom["range_deg"] - 40) < 2


def test_untracked_angle_reads_none() -> None:
    t = np.arange(10) / 30.0
    assert range_of_motion(t, {"knee_flexion_L": np.full(10, np.nan)})["knee_flexion_L"]["range_deg"] is None
