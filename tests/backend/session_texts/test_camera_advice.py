"""Camera advice in plain words from where the body was in the camera's view."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from backend.session_texts.camera_advice import camera_advice, out_of_view_fractions
from kinect_agent.skeleton import INDEX, INFERRED, NOT_TRACKED
from tests.kinect_agent.analysis._data import noisy, uiprmd

SEEDS = (1, 2, 3)


def _codes(rec) -> list[str]:
    return [a["code"] for a in camera_advice(rec)]


def _moved(rec, dx=0.0, dy=0.0, dz=0.0):
    return rec.replace(step="test: moved", positions=rec.positions + np.array([dx, dy, dz]), state=rec.state)


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("exercise", ["squat", "shoulder_abduction", "seated_knee_extension"])
def test_the_simulators_camera_set_up_needs_no_advice(exercise: str, seed: int) -> None:
    measured, _ = noisy(exercise, 3, seed)
    assert camera_advice(measured) == []


@pytest.mark.parametrize("seed", SEEDS)
def test_too_close_and_too_far(seed: int) -> None:
    measured, _ = noisy("squat", 3, seed)
    z = float(np.nanmedian(measured.positions[:, INDEX["ROOT"], 2]))
    close = camera_advice(_moved(measured, dz=1.1 - z))
    assert close[0]["code"] == "too_close" and "1.1 m" in close[0]["text"]
    assert "too_far" in _codes(_moved(measured, dz=4.5 - z))


@pytest.mark.parametrize("seed", SEEDS)
def test_off_centre(seed: int) -> None:
    measured, _ = noisy("squat", 3, seed)
    advice = camera_advice(_moved(measured, dx=1.0))
    assert [a["code"] for a in advice] == ["off_centre"] and "1.0 m to one side" in advice[0]["text"]


@pytest.mark.parametrize("seed", SEEDS)
def test_a_hand_out_of_view_is_named(seed: int) -> None:
    measured, _ = noisy("shoulder_abduction", 3, seed)
    state = measured.state.copy()
    lost = np.random.default_rng(seed).random(measured.n_frames) < 0.4
    state[lost, INDEX["HAN_R"]] = NOT_TRACKED
    advice = camera_advice(measured.replace(step="test", positions=measured.positions, state=state))
    assert [a["code"] for a in advice] == ["hand_out_of_view"] and "your right hand" in advice[0]["text"]


def test_a_hand_inferred_alone_is_not_out_of_view() -> None:
    measured, _ = noisy("shoulder_abduction", 3, 1)
    state = measured.state.copy()
    present = state != NOT_TRACKED  # a lost joint-frame (NaN) stays lost
    hand, wrist = INDEX["HAN_L"], INDEX["WRI_L"]
    state[present[:, hand], hand] = INFERRED  # UI-PRMD: no hand joint, always inferred, wrist tracked
    assert (
        out_of_view_fractions(measured.replace(step="t", positions=measured.positions, state=state))[("hand", "left")]
        < 0.05
    )
    state[present[:, wrist], wrist] = INFERRED  # the sensor infers both when the arm leaves the picture
    assert (
        out_of_view_fractions(measured.replace(step="t", positions=measured.positions, state=state))[("hand", "left")]
        == 1.0
    )


@pytest.mark.parametrize("seed", SEEDS)
def test_feet_at_the_bottom_edge_are_cut_off(seed: int) -> None:
    measured, _ = noisy("squat", 3, seed)
    z = float(np.nanmedian(measured.positions[:, INDEX["FOO_L"], 2]))
    foot_y = float(np.nanmedian(measured.positions[:, INDEX["FOO_L"], 1]))
    drop = -np.tan(np.radians(29.0)) * z - foot_y  # feet 29° below the axis; the view ends at 30°
    assert "feet_cut_off" in _codes(_moved(measured, dy=drop))


@pytest.mark.shared_data
@pytest.mark.parametrize("movement", ["m01", "m07"])
def test_uiprmd_recordings_need_no_advice(data_dir: Path, movement: str) -> None:
    assert camera_advice(uiprmd(data_dir, movement, "s02")) == []
