"""Quaternion and rotation helpers: unit quaternions, round trips, frames."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from kinect_agent.body import rotations as rot

finite = st.floats(-10.0, 10.0, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(arrays(np.float64, (5, 3), elements=finite))
def test_rotvec_gives_unit_quaternions_and_orthonormal_matrices(v: np.ndarray) -> None:
    q = rot.quat_from_rotvec(v)
    np.testing.assert_allclose(np.linalg.norm(q, axis=-1), 1.0, atol=1e-12, err_msg="quaternion not unit")
    R = rot.quat_to_matrix(q)
    np.testing.assert_allclose(R @ np.swapaxes(R, -1, -2), np.broadcast_to(np.eye(3), R.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-12)
    np.testing.assert_allclose(rot.rotvec_to_matrix(v), R, atol=1e-10, err_msg="Rodrigues != quaternion matrix")


@settings(max_examples=60, deadline=None)
@given(arrays(np.float64, (4, 4), elements=finite))
def test_matrix_quaternion_round_trip_is_unit_and_same_rotation(q: np.ndarray) -> None:
    q = q + np.array([1e-3, 0.0, 0.0, 0.0])  # avoid the zero quaternion
    R = rot.quat_to_matrix(q)
    q2 = rot.matrix_to_quat(R)
    np.testing.assert_allclose(np.linalg.norm(q2, axis=-1), 1.0, atol=1e-12)
    np.testing.assert_allclose(rot.quat_to_matrix(q2), R, atol=1e-9)
    product = rot.quat_multiply(q2, rot.quat_conjugate(q2))
    np.testing.assert_allclose(product, np.tile([1.0, 0, 0, 0], (4, 1)), atol=1e-12)


def test_axis_rotation_matches_rotvec(rng: np.random.Generator) -> None:
    angles = rng.uniform(-3, 3, 7)
    for axis in range(3):
        v = np.zeros((7, 3))
        v[:, axis] = angles
        np.testing.assert_allclose(rot.axis_rotation(axis, angles), rot.rotvec_to_matrix(v), atol=1e-12)


def test_matrix_to_rotvec_inverts_rotvec(rng: np.random.Generator) -> None:
    v = rng.normal(size=(50, 3))
    v *= (rng.uniform(0, 3.0, 50) / np.linalg.norm(v, axis=1))[:, None]  # angles below pi
    np.testing.assert_allclose(rot.matrix_to_rotvec(rot.rotvec_to_matrix(v)), v, atol=1e-9)


def test_quat_mean_of_identical_rotations_is_that_rotation(rng: np.random.Generator) -> None:
    q = rot.quat_normalize(rng.normal(size=4))
    many = np.stack([q, -q, q])  # sign flips describe the same rotation
    np.testing.assert_allclose(np.abs(rot.quat_mean(many) @ q), 1.0, atol=1e-12)


def test_frame_from_axes_is_a_rotation_with_the_given_y(rng: np.random.Generator) -> None:
    y, hint = rng.normal(size=(10, 3)), rng.normal(size=(10, 3))
    F = rot.frame_from_axes(y, hint)
    np.testing.assert_allclose(F @ np.swapaxes(F, -1, -2), np.broadcast_to(np.eye(3), F.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(F), 1.0, atol=1e-12)
    np.testing.assert_allclose(F[..., :, 1], y / np.linalg.norm(y, axis=-1, keepdims=True), atol=1e-12)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_compiled_matrix_to_quat_equals_numpys_bit_for_bit(seed: int) -> None:
    """Above COMPILED_MIN_MATRICES the kernel runs: the same bits as numpy's, signs of zero included, on rotations,
    noisy rotations, arbitrary matrices, half turns (ties of the candidates) and a NaN."""
    rng = np.random.default_rng(seed)
    n = rot.COMPILED_MIN_MATRICES
    R = rot.rotvec_to_matrix(2.0 * rng.normal(size=(n, 3)))
    cases = {
        "rotations": R,
        "noisy": R + 1e-3 * rng.normal(size=R.shape),
        "arbitrary": rng.normal(size=(2, n // 2, 3, 3)),
        "special": np.concatenate(
            [
                np.broadcast_to(np.diag(d), (n // 4, 3, 3))
                for d in ([1.0, 1, 1], [-1.0, -1, 1], [1.0, -1, -1], [-1.0, 1, -1])
            ]
        ),  # fmt: skip
    }
    cases["special"][5, 0, 0] = np.nan
    for name, M in cases.items():
        got, ref = rot.matrix_to_quat(M), rot.matrix_to_quat(M, compiled=False)
        np.testing.assert_array_equal(got, ref, err_msg=name)
        np.testing.assert_array_equal(np.signbit(got), np.signbit(ref), err_msg=name)
