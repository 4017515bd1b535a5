"""The chain model F (DoF per joint), its compiled form, and inverse kinematics (FK/IK round trip)."""

from __future__ import annotations

import numpy as np
import pytest

from kinect_agent import skeleton
from kinect_agent.body import _fk_numba
from kinect_agent.body import kinematics as km
from kinect_agent.processing.ik import fill_gaps, inverse_kinematics
from tests.kinect_agent.processing._data import smooth_motion


def _random_model(rng: np.random.Generator) -> km.ChainModel:
    rest = km.REST_DIRECTIONS + rng.normal(0, 0.2, (km.N_BONES, 3))
    rest /= np.linalg.norm(rest, axis=1, keepdims=True)
    R_ref = np.linalg.qr(rng.normal(size=(7, 3, 3)))[0]
    R_ref *= np.sign(np.linalg.det(R_ref))[:, None, None]
    return km.ChainModel(rest, R_ref)


def test_state_has_the_papers_degrees_of_freedom() -> None:
    assert km.N_THETA == sum(skeleton.DOF.values()) == 33
    assert len(km.ROT_JOINTS) == 15


def test_chain_keeps_bone_lengths(rng: np.random.Generator) -> None:
    model = _random_model(rng)
    lengths = rng.uniform(0.05, 0.5, (4, km.N_BONES))
    p = model.positions(rng.normal(size=(4, 3)), lengths, rng.normal(size=(4, km.N_THETA)))
    np.testing.assert_allclose(skeleton.bone_lengths(p), lengths, atol=1e-12)


@pytest.mark.skipif(not _fk_numba.AVAILABLE, reason="numba not installed")
def test_compiled_kernel_equals_numpy(rng: np.random.Generator) -> None:
    model = _random_model(rng)
    args = (rng.normal(size=(9, 3)), rng.uniform(0.1, 0.5, (9, km.N_BONES)), rng.normal(size=(9, km.N_THETA)) * 2)
    args[2][0] = 0.0  # exercises the small-angle branch
    np.testing.assert_allclose(model.positions_compiled(*args), model.positions_numpy(*args), atol=1e-12)


def test_standard_rotations_rebuild_positions_with_forward_kinematics(rng: np.random.Generator) -> None:
    model = _random_model(rng)
    root, theta = rng.normal(size=(6, 3)), rng.normal(size=(6, km.N_THETA))
    lengths = np.broadcast_to(km.TYPICAL_LENGTHS, (6, km.N_BONES))
    R_world_root, R_local = model.standard_rotations(theta)
    np.testing.assert_allclose(
        km.forward_kinematics(root, R_world_root, lengths, R_local), model.positions(root, lengths, theta), atol=1e-12
    )


def test_ik_round_trip_reproduces_positions(rng: np.random.Generator) -> None:
    _, positions, lengths = smooth_motion(120, rng)
    ik = inverse_kinematics(positions)
    np.testing.assert_allclose(ik.lengths, lengths, atol=1e-9, err_msg="bone lengths")
    rebuilt = ik.model.positions(ik.root, np.broadcast_to(ik.lengths, (120, km.N_BONES)), ik.theta)
    err = np.linalg.norm(rebuilt - positions, axis=-1)
    assert err.max() < 0.005, f"IK/FK round trip error {err.max() * 1000:.1f} mm at joint {err.max(0).argmax()}"


def test_ik_handles_missing_joints_and_frames(rng: np.random.Generator) -> None:
    _, positions, _ = smooth_motion(60, rng)
    positions[10:20] = np.nan  # whole frames
    positions[:, skeleton.INDEX["HAN_L"]] = np.nan  # a joint never seen
    ik = inverse_kinematics(positions)
    assert np.all(np.isfinite(ik.theta)) and np.all(np.isfinite(ik.root))
    assert np.isclose(ik.lengths[skeleton.INDEX["HAN_L"] - 1], km.TYPICAL_LENGTHS[skeleton.INDEX["HAN_L"] - 1])


def test_fill_gaps_refuses_an_empty_recording() -> None:
    with pytest.raises(ValueError, match="no joint is observed"):
        fill_gaps(np.full((3, skeleton.J, 3), np.nan))


def test_ik_names_a_wrong_shape() -> None:
    with pytest.raises(ValueError, match=r"positions must have shape \(T>=1, 20, 3\), got \(5, 19, 3\)"):
        inverse_kinematics(np.zeros((5, 19, 3)))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_folding_large_rotations_into_the_references_keeps_the_pose(seed: int) -> None:
    rng = np.random.default_rng(seed)
    model = _random_model(rng)
    root, lengths = rng.normal(size=3), rng.uniform(0.1, 0.5, km.N_BONES)
    theta = rng.normal(size=km.N_THETA) * 1.5  # several 3-DoF rotation vectors longer than 1.5 rad
    before = model.positions(root, lengths, theta)
    folded = theta.copy()
    model.fold_references(folded)
    v = folded[km.THETA_3DOF].reshape(-1, 3)
    assert np.all(np.linalg.norm(v, axis=1) <= 1.5) and not np.allclose(folded, theta)
    np.testing.assert_allclose(model.positions(root, lengths, folded), before, atol=1e-12)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_rebasing_angles_onto_other_references_keeps_the_poses(seed: int) -> None:
    rng = np.random.default_rng(seed)
    old, new = _random_model(rng), _random_model(rng)
    new.rest[:] = old.rest
    theta = rng.normal(size=(5, km.N_THETA))
    root, lengths = rng.normal(size=(5, 3)), rng.uniform(0.1, 0.5, (5, km.N_BONES))
    rebased = new.rebase(theta, np.broadcast_to(old.R_ref, (5, 7, 3, 3)))
    np.testing.assert_allclose(new.positions(root, lengths, rebased), old.positions(root, lengths, theta), atol=1e-12)
