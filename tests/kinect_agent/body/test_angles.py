"""Clinical angles: shoulder rotation is read only where the upper arm is raised enough for "up" to give its sign."""

from __future__ import annotations

import numpy as np
import pytest

from kinect_agent.body import angles
from kinect_agent.body.angles import ROTATION_MIN_ELEVATION_DEG, joint_angles
from kinect_agent.body.kinematics import TYPICAL_LENGTHS, forward_kinematics
from kinect_agent.sources import motions


def _pose(abduction_deg: float, rotation_deg: float, elbow_deg: float = 90.0) -> np.ndarray:
    """Returns (1, J, 3) m: the left arm raised sideways by abduction_deg, turned by rotation_deg, elbow bent."""
    ch = {name: np.zeros(1) for name in motions.CHANNELS}
    ch["sho_abd_L"][:], ch["sho_rot_L"][:], ch["elb_L"][:] = abduction_deg, rotation_deg, elbow_deg
    R = motions.local_rotations(ch, np.random.default_rng(0), np.zeros(1))
    return forward_kinematics(np.zeros((1, 3)), np.eye(3)[None], TYPICAL_LENGTHS[None], R)


@pytest.mark.parametrize("rotation_deg", [-40.0, 0.0, 45.0, 90.0])
def test_rotation_of_an_abducted_arm_reads_the_forearms_turn(rotation_deg):
    got = joint_angles(_pose(88.0, rotation_deg))["shoulder_rotation_L"][0]
    assert abs(got - rotation_deg) < 5.0, got  # the wrist's and neck's natural motion adds a few degrees


@pytest.mark.parametrize("abduction_deg", [0.0, 10.0, 0.6 * ROTATION_MIN_ELEVATION_DEG])
def test_rotation_of_a_hanging_arm_is_undefined(abduction_deg):
    """A hanging arm's forearm read anywhere from -150° to 160° under simulated Kinect noise (an idle arm beside a
    shoulder rotation then outweighed the moving one and the count was 10-12 for 8)."""
    assert np.isnan(joint_angles(_pose(abduction_deg, 0.0, 22.0))["shoulder_rotation_L"][0])


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_three_term_dot_adds_as_numpy_sums_a_contiguous_axis(seed: int) -> None:
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(50, 67, 3)) * 10.0 ** rng.integers(-6, 6, size=(50, 67, 3))
    b = rng.normal(size=(50, 67, 3))
    for x in (a, b):  # signed zeros: (−0) + (−0) + (−0) reads +0 in np.sum, the case an order without 0 + gets wrong
        x[rng.random(x.shape) < 0.3] = 0.0
        x[rng.random(x.shape) < 0.3] = -0.0
    want = np.sum(a * b, axis=-1)
    got = angles._dot(a, b)
    np.testing.assert_array_equal(got.view(np.int64), want.view(np.int64), err_msg="bits of the sums")
    np.testing.assert_array_equal(angles._dot(a, b[0, 0]), np.sum(a * b[0, 0], axis=-1), err_msg="broadcast")
