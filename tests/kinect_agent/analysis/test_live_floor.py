"""The webcam's amplitude floor, measured on each set (kinect_agent.analysis.live.amplitude_floor, NoiseFloor): shallow
repetitions count when the landmarker is steady, its wobble on a person standing still does not, and the live count
and the stored count use the same floor.

Before (a fixed floor of 20 degrees for the webcam): the shallow sets below counted 0 of 5, live and stored
(bench/README.md, "Webcam counts: a floor measured on the set").
"""

from __future__ import annotations

import numpy as np
import pytest

from kinect_agent.analysis.exercise import EXERCISES
from kinect_agent.analysis.live import DEVICE_NOISE_FLOOR, LiveCount, amplitude_floor, counting_params
from kinect_agent.analysis.repetitions import START_S
from kinect_agent.analysis.report import analyze_recording
from kinect_agent.formats.session_file import on_grid
from kinect_agent.processing.config import config_for_device
from kinect_agent.processing.joint_smoother import forward_joints
from kinect_agent.processing.online import live_filter
from kinect_agent.recording import Recording
from kinect_agent.sources.simulator import simulate, simulate_truth
from tests.webcam_like import webcam_like

SEEDS = (0, 1, 2)
EXERCISES_SHALLOW = ("squat", "shoulder_abduction", "standing_leg_raise")
REPS = 5


def _webcam_set(exercise: str, seed: int, amplitude_deg: float, wobble_m: float) -> Recording:
    """Returns a webcam-like set (no swaps) on the session file's grid, as the server stores it."""
    raw = webcam_like(simulate_truth(exercise, REPS, seed=seed, amplitude_deg=amplitude_deg), seed, False, wobble_m)
    return raw.replace(positions=on_grid(raw.positions))


def _live(raw: Recording, names: tuple[str, ...]) -> LiveCount:
    """Returns the camera set's live counter after every frame of raw (the server's path, frame by frame)."""
    filt, counter = live_filter(config_for_device("webcam")), LiveCount(names, device="webcam")
    for k in range(raw.n_frames):
        t = float(raw.t[k])
        counter.add(t, raw.positions[k], raw.state[k], filt.step(t, raw.positions[k], raw.state[k]))
    return counter


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("exercise", EXERCISES_SHALLOW)
def test_shallow_repetitions_seen_by_a_steady_landmarker_count(exercise, seed):
    raw = _webcam_set(exercise, seed, 15.0, 0.0)
    spec = EXERCISES[exercise]
    counter = _live(raw, tuple(spec.defining_angles))
    live, stored = counter.final(), analyze_recording(raw, spec).repetitions
    assert live == stored == REPS, f"{exercise} seed {seed}: live {live}, stored {stored}, floor {counter.floor_deg}"


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("exercise", EXERCISES_SHALLOW)
def test_the_wobble_of_a_person_standing_still_counts_nothing(exercise, seed):
    raw = _webcam_set(exercise, seed, 0.0, 0.005)  # the knee wobbles by up to about 17 degrees
    spec = EXERCISES[exercise]
    counter = _live(raw, tuple(spec.defining_angles))
    live, stored = counter.final(), analyze_recording(raw, spec).repetitions
    assert live == stored == 0, f"{exercise} seed {seed}: live {live}, stored {stored}, floor {counter.floor_deg}"


@pytest.mark.parametrize("seed", SEEDS)
def test_live_and_stored_measure_one_floor_once_the_first_second_is_over(seed):
    raw = _webcam_set("squat", seed, 15.0, 0.0)
    names = tuple(EXERCISES["squat"].defining_angles)
    filt, counter = live_filter(config_for_device("webcam")), LiveCount(names, device="webcam")
    bound = DEVICE_NOISE_FLOOR["webcam"]
    for k in range(raw.n_frames):
        t = float(raw.t[k])
        counter.add(t, raw.positions[k], raw.state[k], filt.step(t, raw.positions[k], raw.state[k]))
        if t <= raw.t[0] + START_S:
            assert counter.floor_deg is None and counter.params.min_amplitude_deg == bound.max_deg, t
    stored = amplitude_floor("webcam", raw.t, forward_joints(raw, config_for_device("webcam")), names)
    assert counter.floor_deg == stored, f"seed {seed}: live floor {counter.floor_deg}, stored {stored}"
    assert stored is not None and bound.min_deg <= stored < bound.max_deg, stored
    assert counter.params.min_amplitude_deg == stored


def test_a_wobbling_landmarker_raises_the_floor_to_its_bound():
    names = tuple(EXERCISES["squat"].defining_angles)
    config = config_for_device("webcam")
    floors = {}
    for wobble_m in (0.0, 0.02):
        raw = _webcam_set("squat", 1, 0.0, wobble_m)
        floors[wobble_m] = amplitude_floor("webcam", raw.t, forward_joints(raw, config), names)
    cap, low = DEVICE_NOISE_FLOOR["webcam"].max_deg, floors[0.0]
    assert cap is not None and low is not None and floors[0.02] == cap > low, floors


def test_a_set_shorter_than_its_first_second_has_no_floor_yet_and_the_kinect_none():
    raw = _webcam_set("squat", 0, 15.0, 0.0)
    names = tuple(EXERCISES["squat"].defining_angles)
    short = raw.t <= raw.t[0] + START_S
    assert amplitude_floor("webcam", raw.t[short], raw.positions[short], names) is None
    assert counting_params("webcam").min_amplitude_deg == DEVICE_NOISE_FLOOR["webcam"].max_deg
    measured, _, _ = simulate("squat", 2, seed=0)
    assert amplitude_floor(measured.meta.device, measured.t, measured.positions, names) == 0.0
    assert counting_params(measured.meta.device).min_amplitude_deg == 0.0
    assert LiveCount(names).floor_deg == 0.0 and LiveCount(names, device="kinect2").params.min_amplitude_deg == 0.0
    assert np.isclose(counting_params("webcam", 9.5).min_amplitude_deg, 9.5)
