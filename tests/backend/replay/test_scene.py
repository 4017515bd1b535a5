"""The replay recording: what it shows (skeletons, outlier marks, camera) and that viser's format holds it."""

from __future__ import annotations

import numpy as np
import pytest

from backend.replay import scene
from kinect_agent import skeleton
from kinect_agent.formats.session_file import SessionPayload
from kinect_agent.recording import Recording
from kinect_agent.sources.simulator import simulate
from tests.backend.replay.viser_file import node_points, read_viser
from tests.kinect_agent.analysis._data import uiprmd

SEEDS = (1, 2, 3)


def _payload(exercise: str, seed: int, *, filtered: bool = True) -> SessionPayload:
    measured, truth, _ = simulate(exercise, 2, seed=seed)
    return SessionPayload(session_id=f"s{seed}", raw=measured, filtered=truth if filtered else None)


def _filtered(payload: SessionPayload) -> Recording:
    assert payload.filtered is not None, "a payload made with its filtered recording"
    return payload.filtered


def test_bone_points_pairs_parent_and_child_joints():
    positions = np.arange(skeleton.J * 3, dtype=float).reshape(skeleton.J, 3)
    bones = scene.bone_points(positions)
    assert bones.shape == (len(skeleton.BONES), 2, 3)
    parent, child = skeleton.BONES[0]
    np.testing.assert_allclose(bones[0], positions[[parent, child]], err_msg="first bone = (parent, child)")


def test_bone_points_refuses_a_wrong_shape():
    with pytest.raises(ValueError, match=r"\(20, 3\)"):
        scene.bone_points(np.zeros((19, 3)))


@pytest.mark.parametrize("seed", SEEDS)
def test_ground_frame_puts_feet_on_the_floor_and_root_above_the_origin(seed):
    payload = _payload("squat", seed)
    shifted = _filtered(payload).positions - scene.ground_frame(_filtered(payload).positions)
    feet = shifted[:, [skeleton.INDEX["FOO_L"], skeleton.INDEX["FOO_R"]], 1]
    assert abs(np.nanpercentile(feet, 2)) < 1e-9
    root = np.nanmedian(shifted[:, skeleton.INDEX["ROOT"]], axis=0)
    np.testing.assert_allclose(root[[0, 2]], 0.0, atol=1e-9, err_msg="ROOT above the origin")
    assert 0.7 < root[1] < 1.3, f"standing ROOT height {root[1]:.2f} m"


@pytest.mark.parametrize("seed", SEEDS)
def test_camera_looks_from_the_side_for_sagittal_and_from_the_front_otherwise(seed):
    positions = _filtered(_payload("squat", seed)).positions
    positions = positions - scene.ground_frame(positions)
    sho_axis = np.nanmedian(positions[:, skeleton.INDEX["SHO_R"]] - positions[:, skeleton.INDEX["SHO_L"]], axis=0)
    sho_axis = sho_axis / np.linalg.norm(sho_axis)
    for plane, view, along_shoulders in (("sagittal", "side", True), ("frontal", "front", False)):
        camera, look_at, got = scene.camera_pose(positions, plane)
        assert got == view
        sight = np.subtract(camera, look_at)
        sight[1] = 0.0
        cos = abs(float(sight @ sho_axis)) / np.linalg.norm(sight)
        assert (cos > 0.95) if along_shoulders else (cos < 0.3), f"{plane}: |cos| to the shoulder axis {cos:.2f}"
    camera, _, _ = scene.camera_pose(positions, "frontal")
    assert camera[2] < 0, "the front view stands where the Kinect was (negative z of the patient)"


def test_frame_indices_thin_fast_recordings_only():
    assert len(scene.frame_indices(np.arange(300) / 30.0)) == 300
    assert len(scene.frame_indices(np.arange(600) / 60.0)) == 300
    assert len(scene.frame_indices(np.array([0.0]))) == 1


@pytest.mark.parametrize("seed", SEEDS)
def test_outlier_flags_find_a_joint_the_camera_lost(seed):
    payload = _payload("shoulder_abduction", seed)
    raw = payload.raw
    before = scene.outlier_flags(raw)  # the simulator's own tracking losses
    wrist = skeleton.INDEX["WRI_R"]
    lost = slice(60, 65)
    raw.positions[lost, wrist] += np.array([0.6, -0.4, 0.3])  # a 1/6 s jump away and back
    flags = scene.outlier_flags(raw)
    assert flags[lost, wrist].mean() > 0.8, f"flagged {flags[lost, wrist].mean():.0%} of the lost samples"
    others = np.ones_like(flags)
    others[lost, wrist] = False
    new = flags & ~before
    assert new[others].mean() < 0.002, f"{new[others].mean():.1%} of the other samples newly flagged"


@pytest.mark.parametrize("seed", SEEDS)
def test_recording_plays_both_skeletons_frame_by_frame(seed):
    payload = _payload("squat", seed)
    replay = scene.build(payload, "sagittal")
    doc = read_viser(replay.data)
    duration = payload.raw.t[-1] - payload.raw.t[0]
    assert doc["durationSeconds"] == pytest.approx(duration, abs=0.05)
    assert replay.n_frames == payload.raw.n_frames and replay.view == "side"
    for name in ("/raw/joints", "/raw/bones", "/filtered/joints", "/filtered/bones"):
        frames = node_points(doc, name)
        assert len(frames) >= 0.95 * replay.n_frames, f"{name}: {len(frames)} updates for {replay.n_frames} frames"
    # the filtered joints played at time t are the stored filtered positions of the frame at t, in the ground frame
    shift = scene.ground_frame(_filtered(payload).positions)
    times, points = zip(*node_points(doc, "/filtered/joints"), strict=True)
    k = len(times) // 2
    frame = int(np.argmin(np.abs((payload.raw.t - payload.raw.t[0]) - times[k])))
    np.testing.assert_allclose(points[k], _filtered(payload).positions[frame] - shift, atol=2e-3,
                               err_msg="filtered joints at mid-session")  # fmt: skip
    camera = [m for _, m in doc["messages"] if m["type"] == "SetCameraPositionMessage"]
    assert camera, "the recording sets the default camera"


def test_outliers_are_marked_on_the_raw_skeleton_when_flagged():
    payload = _payload("squat", 4)
    hand = skeleton.INDEX["HAN_L"]
    payload.raw.positions[90:95, hand] += np.array([0.0, 0.8, -0.5])
    doc = read_viser(scene.build(payload, "sagittal").data)
    shift = scene.ground_frame(_filtered(payload).positions)
    t = payload.raw.t - payload.raw.t[0]
    hits = 0
    for when, points in node_points(doc, "/raw/outliers"):
        frame = int(np.argmin(np.abs(t - when)))
        if 90 <= frame < 95:
            hits += bool(np.any(np.linalg.norm(points - (payload.raw.positions[frame, hand] - shift), axis=1) < 0.01))
    assert hits >= 4, f"the lost hand is marked in {hits} of its 5 frames"


def test_a_file_without_filtered_recording_shows_the_raw_one():
    doc = read_viser(scene.build(_payload("shoulder_abduction", 5, filtered=False), "frontal").data)
    assert node_points(doc, "/raw/joints") and not node_points(doc, "/filtered/joints")


@pytest.mark.shared_data
def test_real_kinect_recording_replays(data_dir):
    raw = uiprmd(data_dir, "m07", "s01")  # standing shoulder abduction, real Kinect v2, 10 repetitions
    replay = scene.build(SessionPayload(session_id="uiprmd", raw=raw), "frontal")
    doc = read_viser(replay.data)
    assert replay.view == "front"
    frames = node_points(doc, "/raw/joints")
    assert len(frames) >= 0.95 * replay.n_frames
    heights = np.array([np.max(p[:, 1]) for _, p in frames])
    assert 1.3 < np.median(heights) < 2.2, f"head height above the floor {np.median(heights):.2f} m"
