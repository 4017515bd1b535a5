"""The live count: the server's repetition logic run incrementally on the online filter's output, frame by frame."""

from __future__ import annotations

import numpy as np
import pytest

from kinect_agent.analysis import live, series
from kinect_agent.analysis.angles import counting_angles
from kinect_agent.analysis.exercise import EXERCISES
from kinect_agent.analysis.live import LiveCount, hint, limb_joints
from kinect_agent.analysis.repetitions import count_repetitions
from kinect_agent.body.angles import body_frame, joint_angles
from kinect_agent.processing.online import OnlineFilter
from kinect_agent.skeleton import INDEX
from kinect_agent.sources.simulator import simulate

SEEDS = (0, 1, 2)
# The motions these tests were written for, and the deep squat: its live count showed 10 for 5 at seed 1 (one knee's
# online filter started on a mistracked first frame at 104°, so the rest level taken from the first value was the
# squat's depth; issue 24). The other eight UI-PRMD movements count 5 of 5 live at seeds 0-2 (bench/README.md) but
# are left out for the suite's time.
SIMULATED = ("shoulder_abduction", "shoulder_flexion", "elbow_flexion", "seated_knee_extension", "squat",
             "sit_to_stand", "standing_leg_raise", "side_step", "deep_squat")  # fmt: skip
REPS = 5
# Alternating hip abduction on the online filter's output: the detector (not the live count) still miscounts some
# sets, offline too (seeds 0-2: 7, 4, 5 of 5 counted on the whole set; after the offline pipeline 5, 5, 5):
# issue "Signal core 2", bench/README.md "Simulated sets as a benchmark".
DETECTOR_WEAK = {"side_step"}


def _run(exercise: str, seed: int, reps: int = REPS):
    """Feeds a simulated set frame by frame; returns (counts shown per frame, final count, t (T,) s, the server's
    count of the whole set filtered the same way)."""
    measured, truth, _ = simulate(exercise, reps, seed=seed)
    names = EXERCISES[exercise].defining_angles
    online, counter = OnlineFilter(), LiveCount(names)
    shown, filtered = [], []
    for i in range(measured.n_frames):
        filtered.append(online.step(measured.t[i], measured.positions[i], measured.state[i]))
        shown.append(counter.add(measured.t[i], measured.positions[i], measured.state[i], filtered[-1]).count)
    smoothed = series.smooth_positions(measured.t, np.array(filtered))
    angles = counting_angles(smoothed, names, joint_angles(smoothed), body_frame(smoothed)[0])
    whole = len(count_repetitions(measured.t, angles, names).repetitions)
    return np.array(shown), counter.final(), measured.t, whole


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("exercise", [e for e in SIMULATED if e not in DETECTOR_WEAK])
def test_live_count_reaches_the_true_count_and_never_goes_back(exercise, seed):
    shown, final, t, _ = _run(exercise, seed)
    assert np.all(np.diff(shown) >= 0), f"{exercise} seed {seed}: the count went down"
    assert final == REPS, f"{exercise} seed {seed}: live count {final}, true {REPS}"
    reached = t[np.argmax(shown >= REPS)] - t[0]
    assert shown[-1] == REPS and reached < t[-1] - t[0], f"{exercise} seed {seed}: the target shows only at the end"


@pytest.mark.parametrize("seed", SEEDS)
def test_a_long_set_keeps_counting_past_the_window(seed):
    """30 repetitions (well over a minute): the window slides and freezes counted repetitions."""
    shown, final, t, whole = _run("elbow_flexion", seed, reps=30)
    assert t[-1] - t[0] > 90
    assert np.all(np.diff(shown) >= 0)
    assert final == whole, f"seed {seed}: live {final}, the server's logic on the whole set {whole}"
    assert abs(final - 30) <= 1, f"seed {seed}: live {final} of 30"


def test_still_seconds_grow_when_nothing_moves():
    frame = simulate("squat", 1, seed=0)[0]
    counter = LiveCount(EXERCISES["squat"].defining_angles)
    pos, state = frame.positions[0], frame.state[0]
    for k in range(300):  # 10 s of one still pose
        status = counter.add(k / 30, pos, state, pos)
    assert status.count == 0 and 9.0 <= status.still_s <= 10.0, status


def test_a_gap_without_frames_is_not_counted_as_still():
    """A browser's pictures stopping mid-set (its landmarker restarting on the page after its worker died: 46 s on a
    loaded CI machine) and coming back: still_s counts the seconds seen (5 s before the gap, 1 s after), not the gap,
    so the set does not end as still (20 s, camera_page.js) on its first picture back."""
    frame = simulate("squat", 1, seed=0)[0]
    counter = LiveCount(EXERCISES["squat"].defining_angles)
    pos, state = frame.positions[0], frame.state[0]
    for t in [k / 30 for k in range(150)] + [45.0 + k / 30 for k in range(31)]:
        status = counter.add(t, pos, state, pos)
    assert 5.5 <= status.still_s <= 6.0 + 1e-9, status


def _frames(shift=(0.0, 0.0, 0.0), untracked=(), n=30):
    rec = simulate("elbow_flexion", 1, seed=1)[0]
    pos = rec.positions[:n] + np.asarray(shift)
    state = rec.state[:n].copy()
    for name in untracked:
        pos[:, INDEX[name]] = np.nan
        state[:, INDEX[name]] = 0
    return pos, state


@pytest.mark.parametrize(
    ("shift", "untracked", "expected"),
    [
        ((0, 0, 0), (), None),
        ((0, 0, -1.6), (), live.HINT_TOO_CLOSE),
        ((0, 0, 2.5), (), live.HINT_TOO_FAR),
        ((1.5, 0, 0), (), live.HINT_OFF_CENTRE),
        ((0, 0, 0), ("ROOT", "SPINE"), live.HINT_OUT_OF_VIEW),
        ((0, 0, 0), ("ELB_L", "WRI_L"), live.HINT_ARMS),
    ],
)
def test_hints_say_what_is_wrong_with_the_view(shift, untracked, expected):
    pos, state = _frames(shift, untracked)
    limbs, kind = limb_joints(EXERCISES["elbow_flexion"].defining_angles)
    assert hint(pos, state, limbs, kind) == expected


def test_leg_exercises_hint_about_legs():
    pos, state = _frames(untracked=("KNE_R", "ANK_R"))
    limbs, kind = limb_joints(EXERCISES["squat"].defining_angles)
    assert kind == "legs" and hint(pos, state, limbs, kind) == live.HINT_LEGS


def test_a_camera_slower_than_one_frame_a_second_still_gets_a_status():
    """A browser landmarker on a slow computer can give under 1 frame/s: the hint uses the newest frame."""
    frame = simulate("squat", 1, seed=0)[0]
    counter = LiveCount(EXERCISES["squat"].defining_angles)
    pos, state = frame.positions[0], frame.state[0]
    for k in range(12):  # one frame every 2.5 s
        status = counter.add(2.5 * k, pos, state, pos)
    assert status.count == 0 and status.hint is None and status.still_s >= 20.0, status
