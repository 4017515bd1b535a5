"""Which metrics a device and view support: all for a depth camera; for a webcam in-plane angles and counts only."""

from __future__ import annotations

import numpy as np
import pytest

from kinect_agent.analysis.validity import angle_validity, session_validity, view_of
from kinect_agent.body.angles import ANGLE_NAMES
from kinect_agent.sources.simulator import simulate


def _turned(positions: np.ndarray, yaw_deg: float) -> np.ndarray:
    """Returns the positions turned about the vertical through the root's mean (camera frame, y up)."""
    a = np.radians(yaw_deg)
    R = np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])
    centre = np.nanmean(positions[:, 0], axis=0)
    return (positions - centre) @ R.T + centre


@pytest.fixture(scope="module")
def facing() -> np.ndarray:
    """A simulated squat with the person facing the camera (view 0)."""
    truth = simulate("squat", 2, seed=1)[1]
    return truth.positions


@pytest.mark.parametrize(("yaw", "view"), [(0, "front"), (180, "front"), (20, "front"), (45, "oblique"),
                                           (90, "side"), (-75, "side")])  # fmt: skip
def test_the_view_comes_from_the_trunk_against_the_camera_axis(facing, yaw, view) -> None:
    found, deg = view_of(_turned(facing, yaw))
    assert found == view, (yaw, found, deg)
    expected = abs(((yaw + 90) % 180) - 90)
    assert deg == pytest.approx(expected, abs=6), (yaw, deg)


def test_a_recording_without_a_trunk_has_an_unknown_view() -> None:
    assert view_of(np.full((50, 20, 3), np.nan)) == ("unknown", None)


def test_a_depth_camera_supports_every_metric(facing) -> None:
    v = session_validity("kinect2", facing, ANGLE_NAMES)
    assert not v.limited and all(m.valid for m in v.metrics.values())


def test_a_webcam_from_the_side_supports_sagittal_angles_and_counts_only(facing) -> None:
    v = session_validity("webcam", _turned(facing, 90), ("knee_flexion_R", "hip_abduction_R", "shoulder_rotation_L"),
                         defining_angle="knee_flexion_R")  # fmt: skip
    assert v.view == "side" and v.limited
    m = v.metrics
    assert m["knee_flexion_R"].valid and m["rom"].valid and m["repetitions"].valid and m["tempo"].valid
    assert not m["hip_abduction_R"].valid and m["hip_abduction_R"].code == "out_of_plane"
    assert "from the front" in (m["hip_abduction_R"].reason or "")
    assert not m["shoulder_rotation_L"].valid and "own axis" in (m["shoulder_rotation_L"].reason or "")
    for name in ("workspace", "balance", "joint_paths"):
        assert not m[name].valid and m[name].code == "metric_scale", name


def test_a_webcam_from_the_front_flags_the_sagittal_range_of_motion(facing) -> None:
    v = session_validity("webcam", facing, ("knee_flexion_R",), defining_angle="knee_flexion_R")
    assert v.view == "front"
    assert not v.metrics["rom"].valid and "from the side" in (v.metrics["rom"].reason or "")
    assert v.metrics["repetitions"].valid
    assert angle_validity("webcam", "front", "shoulder_abduction_L").valid


def test_an_unknown_view_flags_every_webcam_angle() -> None:
    v = session_validity("webcam", None, ("knee_flexion_L", "shoulder_abduction_R"))
    assert v.view == "unknown" and not any(v.metrics[a].valid for a in ("knee_flexion_L", "shoulder_abduction_R"))
    d = v.to_dict()
    assert d["device"] == "webcam" and d["limited"] and {m["name"] for m in d["metrics"]} >= {"rom", "repetitions"}
    with pytest.raises(ValueError, match="unknown angle"):
        angle_validity("webcam", "side", "wrist_flexion")
