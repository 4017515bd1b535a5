"""The embedded calibration tables are the paper's, and the folded-normal solution reproduces them."""

from __future__ import annotations

import numpy as np

from kinect_agent.sources import kinect_noise


def test_embedded_tables_equal_shared_reference(reference_dir):
    for name in kinect_noise.TABLE_FILES:
        embedded = (kinect_noise.CALIBRATION_DIR / name).read_bytes()
        assert embedded == (reference_dir / name).read_bytes(), f"{name} differs from {reference_dir / name}"


def test_tables_cover_every_setting_in_metres():
    tables = kinect_noise.load_tables()
    assert len(tables.offset_mean) == 12
    root_k1 = tables.offset_mean["kinect1", "sitting", 0][0]
    np.testing.assert_allclose(root_k1, 0.256, err_msg="ROOT k1 sitting 0° is 256 mm in the table")
    assert tables.bone_sd["kinect2", "standing", 60].shape == (14,)
    assert tables.gain_pct["kinect2", "standing", 0] == (8.0, 49.0)


def test_folded_normal_parameters_reproduce_mean_and_sd(rng):
    mean = np.array([0.085, 0.256, 0.064, 0.1])
    sd = np.array([0.056, 0.025, 0.031, 0.0])
    mu, sigma = kinect_noise.folded_normal_parameters(mean, sd)
    x = np.abs(mu + sigma * rng.standard_normal((400_000, 4)))
    np.testing.assert_allclose(x.mean(axis=0), mean, rtol=5e-3)
    np.testing.assert_allclose(x.std(axis=0), sd, atol=3e-4)


def test_folded_normal_refuses_impossible_ratio():
    import pytest

    with pytest.raises(kinect_noise.SimulationError, match="folded-normal limit"):
        kinect_noise.folded_normal_parameters(np.array([0.01]), np.array([0.02]))
