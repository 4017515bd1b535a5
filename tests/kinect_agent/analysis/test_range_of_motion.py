"""Range of motion per clinical angle: known ranges, wrapped angles, untracked angles."""

from __future__ import annotations

import numpy as np

from kinect_agent.analysis.range_of_motion import range_of_motion
from kinect_agent.body.angles import joint_angles
from kinect_agent.skeleton import INDEX


def _rom(t: np.ndarray, name: str, angle: np.ndarray) -> dict[str, float]:
    """Returns range_of_motion's min_deg, max_deg and range_deg of one angle, each defined."""
    rom = range_of_motion(t, {name: angle})[name]
    defined = {key: value for key, value in rom.items() if value is not None}
    assert defined.keys() == rom.keys(), rom
    return defined


def test_known_sine_range(rng: np.random.Generator) -> None:
    t = np.arange(600) / 30.0
    x = 50 + 40 * np.sin(2 * np.pi * t / 4.0) + rng.normal(0, 1.5, t.shape)
    rom = _rom(t, "elbow_flexion_L", x)
    assert abs(rom["min_deg"] - 10) < 3 and abs(rom["max_deg"] - 90) < 3 and abs(rom["range_deg"] - 80) < 5


def test_an_arm_swinging_overhead_through_180_has_its_true_range() -> None:
    """The arm swings 150-190° in the frontal plane (atan2 passes ±180°): the angle stays in its domain."""
    t = np.arange(300) / 30.0
    theta = np.radians(170 + 20 * np.sin(2 * np.pi * t / 5.0))
    p = np.zeros((t.size, len(INDEX), 3))
    p[:, INDEX["NECK"]] = [0.0, 0.5, 0.0]
    p[:, INDEX["SHO_L"]], p[:, INDEX["SHO_R"]] = [0.2, 0.45, 0.0], [-0.2, 0.45, 0.0]
    p[:, INDEX["ELB_L"]] = np.array([0.2, 0.45, 0.0]) + 0.3 * np.stack(
        [np.sin(theta), -np.cos(theta), np.zeros_like(theta)], axis=1
    )
    angle = joint_angles(p)["shoulder_abduction_L"]
    assert np.all((angle >= 145) & (angle <= 195))
    rom = _rom(t, "shoulder_abduction_L", angle)
    assert abs(rom["range_deg"] - 40) < 2 and 185 < rom["max_deg"] < 191


def test_untracked_angle_reads_none() -> None:
    t = np.arange(10) / 30.0
    assert range_of_motion(t, {"knee_flexion_L": np.full(10, np.nan)})["knee_flexion_L"]["range_deg"] is None
