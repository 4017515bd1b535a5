"""bench/bone_refit.py: the least-squares bone vectors given the rotations, on synthetic chains with known vectors."""

import numpy as np
import pytest

from bench.bone_refit import refit_bones
from kinect_agent import skeleton
from kinect_agent.body import kinematics as km

SEEDS = (1, 2, 3)


def _chain(seed: int, T: int = 2400) -> tuple[km.ChainModel, np.ndarray, np.ndarray, np.ndarray]:
    """Returns (model, root (T, 3) m, lengths (19,) m, theta (T, 33) rad): a personalised chain moving at random."""
    rng = np.random.default_rng(seed)
    rest = km.REST_DIRECTIONS + rng.normal(0.0, 0.15, km.REST_DIRECTIONS.shape)
    model = km.ChainModel(rest / np.linalg.norm(rest, axis=1, keepdims=True))
    lengths = km.TYPICAL_LENGTHS * rng.uniform(0.85, 1.15, km.N_BONES)
    theta = np.cumsum(rng.normal(0.0, 0.05, (T, km.N_THETA)), axis=0)
    root = np.array([0.0, 0.9, 2.4]) + np.cumsum(rng.normal(0.0, 0.003, (T, 3)), axis=0)
    return model, root, lengths, theta


@pytest.mark.parametrize("seed", SEEDS)
def test_recovers_the_true_vectors_from_wrong_ones(seed: int) -> None:
    model, root, lengths, theta = _chain(seed)
    rng = np.random.default_rng(100 + seed)
    z = model.positions(root, np.broadcast_to(lengths, (len(theta), km.N_BONES)), theta)
    z = z + rng.normal(0.0, 0.03, z.shape)  # 3 cm white noise per axis
    wrong = lengths * rng.uniform(0.85, 1.15, km.N_BONES)  # lengths off by up to 15 %
    out = refit_bones(model, root, wrong, theta, z, np.ones(z.shape[:2]))
    np.testing.assert_allclose(out.lengths, lengths, atol=0.003, err_msg=f"seed {seed}: lengths (m)")
    true_v = model.rest * lengths[:, None]
    new_v = out.model.rest * out.lengths[:, None]
    np.testing.assert_allclose(new_v, true_v, atol=0.003, err_msg=f"seed {seed}: bone vectors (m)")
    np.testing.assert_allclose(out.root, root, atol=0.003, err_msg=f"seed {seed}: root (m)")


@pytest.mark.parametrize("seed", SEEDS)
def test_a_bone_never_observed_keeps_its_vector(seed: int) -> None:
    model, root, lengths, theta = _chain(seed)
    z = model.positions(root, np.broadcast_to(lengths * 1.1, (len(theta), km.N_BONES)), theta)
    weights = np.ones(z.shape[:2])
    hand = skeleton.INDEX["HAN_L"]
    weights[:, hand] = 0.0
    z[:, hand] = np.nan
    out = refit_bones(model, root, lengths, theta, z, weights)
    k = hand - 1  # bone k ends at joint k + 1
    assert out.lengths[k] == pytest.approx(lengths[k], abs=1e-4), f"seed {seed}: unobserved hand bone moved"
    others = np.delete(np.arange(km.N_BONES), k)
    np.testing.assert_allclose(out.lengths[others], 1.1 * lengths[others], atol=1e-3, err_msg=f"seed {seed}")
