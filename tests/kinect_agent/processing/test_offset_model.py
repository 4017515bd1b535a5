"""Tests of the Kinect offset model: a known body-frame offset on a turning, moving body is removed exactly and
recovered by the fit; the pipeline applies it only when asked; the shipped constants load. The validation on real
pairs is in tests/bench/test_offset_model.py."""

from __future__ import annotations

import numpy as np
import pytest

from kinect_agent import skeleton
from kinect_agent.body.rotations import axis_rotation
from kinect_agent.processing import offset_model as om
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.processing.pipeline import process
from kinect_agent.recording import Recording

from ._data import smooth_motion

SEEDS = (1, 2, 3, 4, 5)
FRAME_JOINTS = [skeleton.INDEX[j] for j in ("ROOT", "NECK", "SHO_L", "SHO_R", "HIP_L", "HIP_R")]


def _turning_body(seed: int, frames: int = 120) -> tuple[np.ndarray, np.ndarray]:
    """Returns (truth (T, J, 3) m camera frame, offsets (J, 3) m body frame): smooth joint motion of a body that
    turns by up to +-70 degrees about the vertical and leans by up to 20 degrees; offsets 2-6 cm on the joints that
    do not define the body frame (so the offset body's frame is the truth's)."""
    rng = np.random.default_rng(seed)
    _, p, _ = smooth_motion(frames, rng)
    yaw = np.radians(70.0) * np.sin(np.linspace(0.0, 2.0 * np.pi, frames) + rng.uniform(0, 2 * np.pi))
    lean = np.radians(20.0) * np.sin(np.linspace(0.0, np.pi, frames))
    centre = p[:, :1]
    R = np.stack([axis_rotation(1, y) @ axis_rotation(0, a) for y, a in zip(yaw, lean, strict=True)])
    truth = np.einsum("tab,tjb->tja", R, p - centre) + centre
    offsets = rng.uniform(0.02, 0.06, (skeleton.J, 3)) * rng.choice([-1.0, 1.0], (skeleton.J, 3))
    offsets[FRAME_JOINTS] = 0.0
    return truth, offsets


def _offset_body(truth: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    return truth + np.einsum("tab,jb->tja", om.body_rotation(truth), offsets)


@pytest.mark.parametrize("seed", SEEDS)
def test_apply_removes_a_known_body_frame_offset_on_a_turning_body(seed: int) -> None:
    truth, offsets = _turning_body(seed)
    kinect = _offset_body(truth, offsets)
    model = om.OffsetModel({"all": offsets})
    np.testing.assert_allclose(model.apply(kinect), truth, atol=1e-9, err_msg=f"seed {seed}")
    # the same offsets subtracted in the camera frame (no body rotation) leave centimetres: the rotation matters
    assert np.max(np.linalg.norm(kinect - offsets - truth, axis=-1)) > 0.03


@pytest.mark.parametrize("seed", SEEDS)
def test_fit_recovers_the_offsets_through_noise(seed: int) -> None:
    truth, offsets = _turning_body(seed, frames=300)
    rng = np.random.default_rng(100 + seed)
    kinect = _offset_body(truth, offsets) + rng.normal(0.0, 0.01, truth.shape)
    fitted = om.fit([(kinect, truth)]).offsets_m["all"]
    np.testing.assert_allclose(fitted, offsets, atol=0.004, err_msg=f"seed {seed}")


def test_fit_leaves_joints_without_truth_at_zero_and_averages_trials() -> None:
    truth, offsets = _turning_body(7)
    kinect = _offset_body(truth, offsets)
    unscored = truth.copy()
    unscored[:, skeleton.INDEX["WRI_L"]] = np.nan
    model = om.fit([(kinect, unscored), (_offset_body(truth, 3.0 * offsets), truth)])
    w = skeleton.INDEX["WRI_L"]
    np.testing.assert_allclose(model.offsets_m["all"][w], 3.0 * offsets[w], atol=1e-9)  # one trial has WRI_L
    k = skeleton.INDEX["ELB_R"]
    np.testing.assert_allclose(model.offsets_m["all"][k], 2.0 * offsets[k], atol=1e-9)  # mean of 1x and 3x
    assert not np.any(om.fit([(kinect, unscored)]).offsets_m["all"][w])


@pytest.mark.parametrize("seed", SEEDS[:3])
def test_per_pose_model_uses_each_frames_pose(seed: int) -> None:
    truth, offsets = _turning_body(seed)
    half = len(truth) // 2
    left = om.body_rotation(truth)[half:, :, 0]
    for side in ("L", "R"):  # knees bent 90 degrees in the second half: shank perpendicular to the thigh
        hip, kne = (truth[half:, skeleton.INDEX[f"{n}_{side}"]] for n in ("HIP", "KNE"))
        shank = np.cross(hip - kne, left)
        truth[half:, skeleton.INDEX[f"ANK_{side}"]] = kne + 0.4 * shank / np.linalg.norm(shank, axis=-1, keepdims=True)
    offsets[[skeleton.INDEX[f"{n}_{s}"] for n in ("KNE", "ANK") for s in "LR"]] = 0.0  # keep the knee angles
    pose = om.pose_of(truth)
    assert 0 < pose.sum() < len(pose), f"seed {seed}: the motion should have both poses"
    model = om.OffsetModel({"standing": offsets, "bent": 2.0 * offsets})
    kinect = truth + np.einsum("tab,tjb->tja", om.body_rotation(truth), np.where(pose[:, None, None] == 1, 2.0, 1.0)
                               * offsets)  # fmt: skip
    np.testing.assert_allclose(model.apply(kinect), truth, atol=1e-9, err_msg=f"seed {seed}")


def test_pose_of_tells_seated_from_standing() -> None:
    truth, _ = _turning_body(1, frames=10)
    standing = truth.copy()
    for side in ("L", "R"):  # straight legs below the hips
        hip = standing[:, skeleton.INDEX[f"HIP_{side}"]]
        standing[:, skeleton.INDEX[f"KNE_{side}"]] = hip + [0.0, -0.45, 0.0]
        standing[:, skeleton.INDEX[f"ANK_{side}"]] = hip + [0.0, -0.9, 0.0]
    seated = standing.copy()
    for side in ("L", "R"):  # thigh forward (towards the camera, -z), shank down
        hip = seated[:, skeleton.INDEX[f"HIP_{side}"]]
        seated[:, skeleton.INDEX[f"KNE_{side}"]] = hip + [0.0, 0.0, -0.45]
        seated[:, skeleton.INDEX[f"ANK_{side}"]] = hip + [0.0, -0.45, -0.45]
    assert not om.pose_of(standing).any()
    assert om.pose_of(seated).all()


def test_model_refuses_a_wrong_shape_or_pose() -> None:
    with pytest.raises(ValueError, match=r"expected shape \(20, 3\)"):
        om.OffsetModel({"all": np.zeros((19, 3))})
    with pytest.raises(ValueError, match="unknown pose"):
        om.OffsetModel({"lying": np.zeros((skeleton.J, 3))})
    with pytest.raises(ValueError, match=r"expected shape \(T, 20, 3\)"):
        om.OffsetModel({"all": np.zeros((skeleton.J, 3))}).apply(np.zeros((5, 3)))


def test_shipped_constants_load_with_their_provenance() -> None:
    model = om.load_default()
    assert model.provenance["fitted_by"] == "bench/offset_model.py"
    assert np.all(np.abs(model.offsets_m["all"]) < 0.1), "a shipped offset above 10 cm is not a Kinect bias"
    assert np.any(model.offsets_m["all"] != 0.0)


@pytest.mark.parametrize("seed", SEEDS[:3])
def test_pipeline_applies_the_default_model_only_when_asked(seed: int) -> None:
    rng = np.random.default_rng(seed)
    t, p, _ = smooth_motion(60, rng)
    rec = Recording.from_positions(t, p + rng.normal(0.0, 0.01, p.shape))
    off = process(rec).filtered.positions
    on = process(rec, config=PipelineConfig(offset_model=True)).filtered.positions
    np.testing.assert_allclose(on, om.correct(off), atol=1e-12, err_msg=f"seed {seed}")
    assert np.max(np.abs(on - off)) > 0.01
