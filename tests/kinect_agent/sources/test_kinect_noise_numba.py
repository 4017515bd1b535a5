"""The compiled sweeps of the simulated Kinect noise (_kinect_noise_numba) against the numpy reference, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from kinect_agent import skeleton
from kinect_agent.sources import _kinect_noise_numba, kinect_noise
from kinect_agent.sources.simulator import simulate_truth

pytestmark = pytest.mark.skipif(not _kinect_noise_numba.AVAILABLE, reason="numba is not installed")


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_refine_offsets_compiled_equals_numpy_bit_for_bit(seed):
    rng = np.random.default_rng(seed)
    pos = simulate_truth("squat", 1, seed=seed).positions[::3]
    T, J = pos.shape[:2]
    dist = np.abs(rng.normal(0.02, 0.02, (T, J)))  # m, offset distances
    direction = rng.normal(size=(T, J, 3))
    off = dist[..., None] * direction / np.linalg.norm(direction, axis=-1, keepdims=True)
    wanted = skeleton.bone_lengths(pos) + rng.normal(0.0, 0.01, (T, len(skeleton.BONES)))
    compiled = kinect_noise.refine_offsets(pos, dist, off, wanted)
    reference = kinect_noise.refine_offsets(pos, dist, off, wanted, compiled=False)
    np.testing.assert_array_equal(compiled, reference, err_msg=f"seed {seed}")
    assert not np.array_equal(reference, off), "the sweeps moved nothing: the comparison says nothing"
    np.testing.assert_allclose(np.linalg.norm(compiled, axis=-1), dist, atol=1e-12, err_msg="|offset| = dist")
