"""ReplayManager: one viser server per session, reused, stopped when idle."""

from __future__ import annotations

import httpx
import numpy as np
import pytest

from frontend.replay import ReplayManager, bone_points
from kinect_agent import skeleton
from tests.backend.khs_files import make_khs


def test_bone_points_pairs_parent_and_child_joints():
    positions = np.arange(skeleton.J * 3, dtype=float).reshape(skeleton.J, 3)
    bones = bone_points(positions)
    assert bones.shape == (len(skeleton.BONES), 2, 3)
    parent, child = skeleton.BONES[0]
    np.testing.assert_allclose(bones[0], positions[[parent, child]], err_msg="first bone = (parent, child)")


def test_bone_points_refuses_a_wrong_shape():
    with pytest.raises(ValueError, match=r"\(20, 3\)"):
        bone_points(np.zeros((19, 3)))


def test_open_starts_once_reuses_and_closes_when_idle():
    manager = ReplayManager(idle_s=0.0, check_every_s=3600)
    data = make_khs("squat", 2, seed=3)
    loads = []

    def load() -> bytes:
        loads.append(1)
        return data

    try:
        first = manager.open(7, load)
        again = manager.open(7, load)
        assert again is first and len(loads) == 1, "a second open must reuse the running viewer"
        assert httpx.get(f"http://127.0.0.1:{first.port}/", timeout=10).status_code == 200
        assert first.n_frames > 0
        assert manager.close_idle() == [7]
        assert manager.running() == []
    finally:
        manager.close_all()
