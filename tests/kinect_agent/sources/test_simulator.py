"""The simulator's truth: exact kinematic-chain motion with the requested repetitions."""

from __future__ import annotations

import numpy as np
import pytest

from kinect_agent import skeleton
from kinect_agent.body.angles import joint_angles
from kinect_agent.sources import motions
from kinect_agent.sources.simulator import EXERCISES, SimulationError, simulate, simulate_truth

SERVER_SLUGS = ("shoulder_abduction", "shoulder_flexion", "elbow_flexion", "seated_knee_extension", "squat",
                "sit_to_stand", "standing_leg_raise", "side_step")  # fmt: skip


def test_exercise_list_covers_the_server_library():
    assert set(SERVER_SLUGS) <= set(EXERCISES)


@pytest.mark.parametrize("exercise", EXERCISES)
def test_truth_segment_lengths_are_exactly_constant(exercise):
    rec = simulate_truth(exercise, 3, seed=2)
    lengths = skeleton.bone_lengths(rec.positions)
    np.testing.assert_allclose(lengths, np.broadcast_to(lengths[0], lengths.shape), atol=1e-12)
    np.testing.assert_allclose(lengths[0], rec.meta.extra["bone_lengths_m"], atol=1e-12)


@pytest.mark.parametrize("exercise", EXERCISES)
@pytest.mark.parametrize("reps", [1, 4])
def test_defining_angle_moves_through_its_range_once_per_repetition(exercise, reps):
    rec = simulate_truth(exercise, reps, seed=7)
    spec = motions.SPECS[exercise]
    angles = joint_angles(rec.positions)
    activity = np.max([np.abs(angles[a] - angles[a][0]) for a in spec.angles], axis=0)  # degrees from rest
    above = activity > 0.5 * spec.amplitude
    rises = int(np.sum(above[1:] & ~above[:-1]))
    assert rises == reps, f"{exercise}: the angle rose past half its range {rises} times for {reps} reps"
    bounds = np.asarray(rec.meta.extra["rep_bounds_s"])
    assert bounds.shape == (reps, 2)
    for a, b in bounds:
        peak = activity[(rec.t >= a) & (rec.t <= b + 0.1)].max()
        assert 0.6 * spec.amplitude <= peak <= 1.3 * spec.amplitude, f"{exercise}: peak {peak:.0f}° in rep [{a}, {b}]"


def test_fatigue_lowers_amplitude_and_slows_repetitions():
    rec = simulate_truth("shoulder_abduction", 12, seed=3)
    angle = joint_angles(rec.positions)["shoulder_abduction_L"]
    bounds = np.asarray(rec.meta.extra["rep_bounds_s"])
    peaks = [angle[(rec.t >= a) & (rec.t <= b)].max() for a, b in bounds]
    durations = bounds[:, 1] - bounds[:, 0]
    assert np.mean(peaks[-3:]) < np.mean(peaks[:3])
    assert np.mean(durations[-3:]) > np.mean(durations[:3])


def test_body_size_varies_with_seed_and_feet_stay_on_the_floor():
    a, b = simulate_truth("squat", 2, seed=1), simulate_truth("squat", 2, seed=2)
    assert not np.allclose(a.meta.extra["bone_lengths_m"], b.meta.extra["bone_lengths_m"])
    floor = -motions.CAMERA_HEIGHT_M
    feet_y = a.positions[:, [skeleton.INDEX["FOO_L"], skeleton.INDEX["FOO_R"]], 1]
    assert np.all(np.abs(feet_y - feet_y[0]) < 0.05), "planted feet move less than 5 cm vertically"
    assert np.all(feet_y > floor - 0.05)


def test_simulation_is_deterministic_for_a_seed():
    m1, t1, k1 = simulate("elbow_flexion", 2, device="kinect1", view_deg=30, seed=9)
    m2, t2, k2 = simulate("elbow_flexion", 2, device="kinect1", view_deg=30, seed=9)
    m3, _, _ = simulate("elbow_flexion", 2, device="kinect1", view_deg=30, seed=10)
    np.testing.assert_array_equal(m1.positions, m2.positions)
    np.testing.assert_array_equal(t1.positions, t2.positions)
    np.testing.assert_array_equal(k1, k2)
    assert m1.positions.shape != m3.positions.shape or not np.allclose(m1.positions, m3.positions, equal_nan=True)


def test_metadata_of_measured_and_truth():
    measured, truth, _ = simulate("seated_knee_extension", 2, device="kinect1", view_deg=60, rate_hz=20, seed=1)
    assert truth.meta.device == "simulator" and measured.meta.device == "kinect1"
    assert measured.meta.pose == "sitting" and measured.meta.view_deg == 60.0
    np.testing.assert_allclose(np.diff(truth.t), 1 / 20)
    np.testing.assert_array_equal(measured.t, truth.t)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"exercise": "jumping", "reps": 2}, "known exercises: shoulder_abduction"),
        ({"exercise": "squat", "reps": 0}, "reps must be a whole number"),
        ({"exercise": "squat", "reps": 2, "pose": "sitting"}, "squat cannot be done sitting"),
        ({"exercise": "seated_knee_extension", "reps": 2, "pose": "standing"}, "cannot be done standing"),
        ({"exercise": "squat", "reps": 2, "view_deg": 45}, "view 45"),
        ({"exercise": "squat", "reps": 2, "device": "kinect3"}, "unknown device"),
        ({"exercise": "squat", "reps": 2, "rate_hz": 0.0}, "rate must be between"),
    ],
)
def test_bad_arguments_are_refused_clearly(kwargs, message):
    with pytest.raises(SimulationError, match=message):
        simulate(**kwargs)
