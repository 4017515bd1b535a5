"""BlazePose landmarks -> the 20 joints: the pinhole placement, the joint rules, the axes and the tracking states."""

from __future__ import annotations

import numpy as np
import pytest

from kinect_agent import skeleton
from kinect_agent.sources.webcam.landmarks import LANDMARK, LandmarkBatch
from kinect_agent.sources.webcam.mapping import (
    INFERRED_VISIBILITY,
    SPINE_FRACTION,
    TRACKED_VISIBILITY,
    focal_px,
    hip_translation,
    to_recording,
    to_skeletons,
)

IDX = skeleton.INDEX
SIZE = (1280, 720)


def projected_batch(rng: np.random.Generator, T: np.ndarray, fov: float = 65.0, n: int = 4) -> LandmarkBatch:
    """A batch whose image landmarks are the exact pinhole projection of world + T (MediaPipe axes)."""
    world = rng.normal(0.0, 0.35, (n, 33, 3))
    world[..., 2] *= 0.3  # a body is flatter in depth than it is tall
    f = focal_px(SIZE[0], fov)
    cam = world + T[:, None, :]
    image = np.empty_like(world)
    image[..., 0] = f * cam[..., 0] / cam[..., 2] / SIZE[0] + 0.5
    image[..., 1] = f * cam[..., 1] / cam[..., 2] / SIZE[1] + 0.5
    image[..., 2] = world[..., 2]
    return LandmarkBatch(np.arange(n) / 30.0, world, image, np.full((n, 33), 0.95), SIZE)


@pytest.mark.parametrize("seed", [3, 4, 5, 6])
def test_the_pinhole_fit_recovers_where_the_hips_are(seed) -> None:
    rng = np.random.default_rng(seed)
    T = np.column_stack([rng.uniform(-0.5, 0.5, 4), rng.uniform(-0.3, 0.3, 4), rng.uniform(1.5, 4.0, 4)])
    batch = projected_batch(rng, T)
    batch.image[..., :2] = np.clip(batch.image[..., :2], -0.01, 1.01)  # keep all inside for this check
    inside = np.all((batch.image[..., :2] > -0.01) & (batch.image[..., :2] < 1.01), axis=-1)
    assert inside.mean() > 0.5
    found = hip_translation(batch)
    np.testing.assert_allclose(found, T, atol=0.35, err_msg="clipped points bias the fit little")
    exact = projected_batch(np.random.default_rng(seed), T)
    np.testing.assert_allclose(hip_translation(exact), T, atol=1e-9, err_msg="exact projections: exact hips")


def test_a_wrong_field_of_view_scales_the_distance() -> None:
    T = np.array([[0.1, 0.0, 3.0]] * 4)
    batch = projected_batch(np.random.default_rng(9), T, fov=50.0)
    assumed = hip_translation(batch, fov_deg=65.0)
    ratio = focal_px(SIZE[0], 65.0) / focal_px(SIZE[0], 50.0)
    np.testing.assert_allclose(assumed[:, 2], 3.0 * ratio, rtol=0.02)  # distance scales with the focal length


def test_joints_are_built_from_their_landmarks_in_the_kinect_axes() -> None:
    batch = projected_batch(np.random.default_rng(11), np.array([[0.2, -0.1, 2.5]] * 4))
    out = to_skeletons(batch)
    cam = (batch.world + hip_translation(batch)[:, None, :]) * np.array([-1.0, -1.0, 1.0])
    mid = lambda a, b: (cam[:, LANDMARK[a]] + cam[:, LANDMARK[b]]) / 2  # noqa: E731
    np.testing.assert_allclose(out.positions[:, IDX["ROOT"]], mid("left_hip", "right_hip"), atol=1e-12)
    np.testing.assert_allclose(out.positions[:, IDX["NECK"]], mid("left_shoulder", "right_shoulder"), atol=1e-12)
    np.testing.assert_allclose(out.positions[:, IDX["HEAD"]], mid("left_ear", "right_ear"), atol=1e-12)
    np.testing.assert_allclose(out.positions[:, IDX["HAN_R"]], mid("right_index", "right_pinky"), atol=1e-12)
    spine = out.positions[:, IDX["ROOT"]] + SPINE_FRACTION * (
        out.positions[:, IDX["NECK"]] - out.positions[:, IDX["ROOT"]]
    )
    np.testing.assert_allclose(out.positions[:, IDX["SPINE"]], spine, atol=1e-12)
    for joint, mark in (("ELB_L", "left_elbow"), ("KNE_R", "right_knee"), ("FOO_L", "left_foot_index")):
        np.testing.assert_allclose(out.positions[:, IDX[joint]], cam[:, LANDMARK[mark]], atol=1e-12, err_msg=joint)


def test_up_in_the_image_is_up_and_the_persons_left_is_the_cameras_right() -> None:
    # a person facing the camera: their left hand is on the image's right; the head is above the hips
    rng = np.random.default_rng(2)
    batch = projected_batch(rng, np.array([[0.0, 0.0, 2.0]] * 4))
    batch.world[:, LANDMARK["left_wrist"]] = [0.4, 0.0, 0.0]  # image-right of the hips
    batch.world[:, LANDMARK["left_ear"]] = batch.world[:, LANDMARK["right_ear"]] = [0.0, -0.6, 0.0]  # image-up
    out = to_skeletons(batch)
    root = out.positions[:, IDX["ROOT"]]
    assert np.all(out.positions[:, IDX["HEAD"], 1] > root[:, 1])  # Kinect y up
    assert np.all(out.positions[:, IDX["WRI_L"], 0] < root[:, 0])  # Kinect x to the camera's left
    assert np.all(root[:, 2] > 1.0)  # z away from the camera


def test_tracking_states_follow_visibility_and_the_image_border() -> None:
    batch = projected_batch(np.random.default_rng(5), np.array([[0.0, 0.0, 3.0]] * 4))
    batch.visibility[:] = 0.9
    batch.visibility[0, LANDMARK["left_elbow"]] = TRACKED_VISIBILITY - 0.01
    batch.visibility[1, LANDMARK["left_elbow"]] = INFERRED_VISIBILITY - 0.01
    batch.visibility[2, LANDMARK["right_hip"]] = INFERRED_VISIBILITY - 0.01  # ROOT, SPINE and HIP_R use it
    batch.image[3, LANDMARK["right_foot_index"], :2] = [0.5, 1.2]  # below the image
    out = to_skeletons(batch)
    assert out.state[0, IDX["ELB_L"]] == skeleton.INFERRED and out.state[0, IDX["WRI_L"]] == skeleton.TRACKED
    assert out.state[1, IDX["ELB_L"]] == skeleton.NOT_TRACKED and np.isnan(out.positions[1, IDX["ELB_L"]]).all()
    assert [out.state[2, IDX[j]] for j in ("ROOT", "SPINE", "HIP_R", "HIP_L")] == [0, 0, 0, 2]
    assert out.state[3, IDX["FOO_R"]] == skeleton.INFERRED and out.state[3, IDX["ANK_R"]] == skeleton.TRACKED


def test_a_frame_that_cannot_be_placed_is_not_tracked() -> None:
    batch = projected_batch(np.random.default_rng(8), np.array([[0.0, 0.0, 2.0]] * 4))
    batch.visibility[1] = 0.05  # nobody really seen
    out = to_skeletons(batch)
    assert (out.state[1] == skeleton.NOT_TRACKED).all() and np.isnan(out.positions[1]).all()
    assert (out.state[[0, 2, 3]] != skeleton.NOT_TRACKED).all()
    rec = to_recording(batch)
    assert rec.meta.device == "webcam" and rec.t[0] == 0.0 and rec.meta.extra["webcam"]["fov_deg"] == 65.0
