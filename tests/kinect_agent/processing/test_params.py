"""KinematicParams: shapes, forward kinematics and the JSON round trip."""

from __future__ import annotations

import json

import numpy as np
import pytest

from kinect_agent import skeleton
from kinect_agent.body.rotations import quat_from_rotvec
from kinect_agent.processing.params import KinematicParams


def _params(rng: np.random.Generator, T: int = 5) -> KinematicParams:
    return KinematicParams(
        t=np.arange(T) / 30.0,
        segment_lengths=rng.uniform(0.05, 0.45, 19),
        root=rng.normal(size=(T, 3)),
        q_root=quat_from_rotvec(rng.normal(size=(T, 3))),
        q_local=quat_from_rotvec(rng.normal(size=(T, 19, 3))),
        joint_angles={"elbow_flexion_L": rng.uniform(0, 140, T)},
        outlier_prob=rng.random((T, skeleton.J)),
    )


def test_json_round_trip_keeps_values_to_their_rounding(rng: np.random.Generator) -> None:
    p = _params(rng)
    back = KinematicParams.from_json(json.loads(json.dumps(p.to_json())))
    np.testing.assert_allclose(back.segment_lengths, p.segment_lengths, atol=1e-5)
    np.testing.assert_allclose(back.q_local, p.q_local, atol=1e-5)
    np.testing.assert_allclose(back.joint_angles["elbow_flexion_L"], p.joint_angles["elbow_flexion_L"], atol=0.01)
    np.testing.assert_allclose(back.positions(), p.positions(), atol=1e-3)


def test_positions_keep_the_segment_lengths(rng: np.random.Generator) -> None:
    p = _params(rng)
    np.testing.assert_allclose(skeleton.bone_lengths(p.positions()), np.tile(p.segment_lengths, (5, 1)), atol=1e-12)


def test_shapes_are_checked(rng: np.random.Generator) -> None:
    with pytest.raises(ValueError, match=r"q_local must have shape \(5, 19, 4\), got \(5, 18, 4\)"):
        KinematicParams(np.arange(5.0), np.ones(19), np.zeros((5, 3)), np.ones((5, 4)), np.ones((5, 18, 4)))


def test_from_json_names_what_is_wrong(rng: np.random.Generator) -> None:
    data = _params(rng).to_json()
    with pytest.raises(ValueError, match="not a kinematic-parameters document"):
        KinematicParams.from_json({"format": "other"})
    del data["root_m"]
    with pytest.raises(ValueError, match="lacks the field 'root_m'"):
        KinematicParams.from_json(data)
