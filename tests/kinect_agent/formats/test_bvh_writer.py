"""BVH writer: the file the project's own BVH reader reads back gives the written joint positions (round trip)."""

from __future__ import annotations

import numpy as np
import pytest

from kinect_agent import skeleton
from kinect_agent.body.rotations import axis_rotation, rotvec_to_matrix
from kinect_agent.formats import bvh, bvh_writer
from kinect_agent.formats import session_file as sf
from kinect_agent.sources.simulator import simulate


def _round_trip(tmp_path, t, positions):
    path = tmp_path / "motion.bvh"
    path.write_text(bvh_writer.write_text(t, positions), encoding="utf-8")
    return bvh.read(path)


@pytest.mark.parametrize(
    ("exercise", "seed"),
    [("squat", 0), ("squat", 1), ("elbow_flexion", 2), ("shoulder_abduction", 3), ("side_step", 9)],
)
def test_round_trip_reproduces_the_kinematic_model_within_1_mm(tmp_path, exercise, seed):
    _, truth, _ = simulate(exercise, 2, seed=seed)
    back = _round_trip(tmp_path, truth.t, truth.positions)
    assert back.meta.extra["unit_m"] == 0.01, "the reader must recognise centimetres"
    err_mm = np.linalg.norm(back.positions - truth.positions, axis=-1) * 1000
    worst = np.unravel_index(np.argmax(err_mm), err_mm.shape)
    assert err_mm.max() < 1.0, f"{err_mm.max():.4f} mm at frame {worst[0]} joint {skeleton.JOINTS[worst[1]]}"


@pytest.mark.parametrize("seed", [4, 5, 6])
def test_round_trip_of_the_stored_filtered_recording_stays_within_its_grid(tmp_path, seed):
    """The session file rounds positions to a 2**-10 m grid, so bone lengths vary by up to ~2 mm there; the BVH's
    constant lengths reproduce those positions to well under 1 mm RMS and within the grid's diagonal at worst."""
    _, truth, _ = simulate("squat", 2, seed=seed)
    stored = sf.decode(sf.encode(sf.SessionPayload(session_id="s", raw=truth, filtered=truth))).filtered
    assert stored is not None
    back = _round_trip(tmp_path, stored.t, stored.positions)
    err_mm = np.linalg.norm(back.positions - stored.positions, axis=-1) * 1000
    assert np.sqrt(np.mean(err_mm**2)) < 0.6, f"RMS {np.sqrt(np.mean(err_mm**2)):.3f} mm"
    assert err_mm.max() < 2 * np.sqrt(3) * sf.GRID_M * 1000, f"max {err_mm.max():.3f} mm"


def test_offsets_hold_the_median_segment_lengths(tmp_path):
    _, truth, _ = simulate("squat", 2, seed=7)
    text = bvh_writer.write_text(truth.t, truth.positions)
    path = tmp_path / "m.bvh"
    path.write_text(text, encoding="utf-8")
    with open(path, encoding="utf-8") as f:
        lines = [(n, line.split()) for n, line in enumerate(f, start=1) if line.split()]
    joints, _ = bvh.parse_hierarchy(path, lines)
    by_name = {j.name: j for j in joints}
    lengths = np.median(skeleton.bone_lengths(truth.positions), axis=0) * 100  # cm
    for k, (_, c) in enumerate(skeleton.BONES):
        name = skeleton.JOINTS[c]
        bvh_name = bvh_writer.BVH_NAMES.get(name) or f"{bvh_writer.BVH_NAMES[skeleton.JOINTS[skeleton.PARENT[c]]]}_End"
        np.testing.assert_allclose(np.linalg.norm(by_name[bvh_name].offset), lengths[k], atol=1e-3, err_msg=name)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_euler_angles_compose_back_to_the_rotation_as_the_reader_does(seed):
    rng = np.random.default_rng(seed)
    R = rotvec_to_matrix(rng.normal(size=(500, 3)) * 2.0)
    R[:3] = [axis_rotation(0, a) @ axis_rotation(2, 0.3) for a in (np.pi / 2, -np.pi / 2, np.pi / 2)]  # gimbal
    z, x, y = np.radians(bvh_writer.euler_zxy(R)).T
    rebuilt = axis_rotation(2, z) @ axis_rotation(0, x) @ axis_rotation(1, y)
    np.testing.assert_allclose(rebuilt, R, atol=1e-9)


def test_gaps_are_filled_and_a_joint_never_tracked_is_refused():
    _, truth, _ = simulate("squat", 1, seed=8)
    positions = truth.positions.copy()
    positions[10:20, skeleton.INDEX["WRI_L"]] = np.nan
    text = bvh_writer.write_text(truth.t, positions)
    assert "nan" not in text.lower()
    positions[:, skeleton.INDEX["FOO_R"]] = np.nan
    with pytest.raises(ValueError, match="FOO_R is never tracked"):
        bvh_writer.write_text(truth.t, positions)
