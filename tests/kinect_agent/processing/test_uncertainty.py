"""The per-frame angle SDs: the sigma-point rule against Monte Carlo, the stride against every frame, the pipeline."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from kinect_agent.body.angles import ANGLE_NAMES, joint_angles
from kinect_agent.processing import uncertainty
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.processing.ik import inverse_kinematics
from kinect_agent.processing.pipeline import process, smooth
from kinect_agent.sources.simulator import simulate, simulate_truth

SEEDS = (1, 2, 3)
STRAIGHT_DEG = 15.0  # a hinge within this of straight
# Angles defined away from their singular poses in these motions (shoulder rotation needs a bent elbow).
WELL_DEFINED = ("elbow_flexion_L", "elbow_flexion_R", "knee_flexion_L", "knee_flexion_R", "hip_flexion_L",
                "hip_flexion_R", "trunk_flexion", "trunk_lateral_flexion")  # fmt: skip

NON_NEGATIVE = ("elbow_flexion_L", "elbow_flexion_R", "knee_flexion_L", "knee_flexion_R", "trunk_flexion")


def _frames(seed: int, n: int = 6) -> tuple[Any, ...]:
    truth = simulate_truth("squat", 1, seed=seed)
    ik = inverse_kinematics(truth.positions)
    k = np.linspace(0, truth.n_frames - 1, n).astype(int)
    rng = np.random.default_rng(seed)
    A = rng.normal(0.0, 1.0, (n, 36, 36))
    P = A @ np.swapaxes(A, 1, 2) / 36.0 * 0.02**2  # SDs ≈ 0.02 rad (1.1°), correlated
    return ik, k, P, rng


@pytest.mark.parametrize("seed", SEEDS)
def test_the_sigma_point_sd_matches_monte_carlo_for_small_covariances(seed):
    ik, k, P, rng = _frames(seed)
    sd = uncertainty.model_angle_sd(ik.model, ik.lengths, ik.theta[k], P, stride=1)
    L = np.linalg.cholesky(P)
    draws = np.concatenate((ik.root[k], ik.theta[k]), axis=1)[:, None, :] + np.einsum(
        "fij,fsj->fsi", L, rng.standard_normal((len(k), 4000, 36))
    )
    pos = ik.model.positions(draws[..., :3], np.broadcast_to(ik.lengths, draws.shape[:2] + (19,)), draws[..., 3:])
    ang = joint_angles(pos)
    for a, name in enumerate(ANGLE_NAMES):
        if name not in WELL_DEFINED:
            continue
        mc = np.std(ang[name], axis=1)
        # At a fold (a straight joint reads flexion >= 0 either way) the rule errs on the safe side, by < 70 %.
        fold = np.abs(np.median(ang[name], axis=1)) < 3.0 * mc if name in NON_NEGATIVE else np.zeros(len(mc), bool)
        np.testing.assert_allclose(sd[~fold, a], mc[~fold], rtol=0.12, atol=0.05, err_msg=f"{name}, seed {seed}")
        assert np.all((sd[fold, a] >= 0.95 * mc[fold]) & (sd[fold, a] <= 1.7 * mc[fold])), f"{name} fold, seed {seed}"


def test_the_root_block_of_the_covariance_does_not_change_any_sd():
    ik, k, P, _ = _frames(1)
    sd = uncertainty.model_angle_sd(ik.model, ik.lengths, ik.theta[k], P, stride=1)
    P2 = P.copy()
    P2[:, :3, :3] += np.eye(3) * 0.5**2  # half a metre more root uncertainty
    sd2 = uncertainty.model_angle_sd(ik.model, ik.lengths, ik.theta[k], P2, stride=1)
    np.testing.assert_allclose(sd2, sd, rtol=1e-9, err_msg="angles are differences of positions")


def test_shapes_are_checked():
    ik, k, P, _ = _frames(1)
    with pytest.raises(ValueError, match="P"):
        uncertainty.model_angle_sd(ik.model, ik.lengths, ik.theta[k], P[:, :35, :35])


@pytest.mark.parametrize("seed", SEEDS)
def test_every_fifth_frame_interpolated_is_close_to_every_frame(seed):
    measured, _, _ = simulate("squat", 2, seed=seed)
    ik = inverse_kinematics(measured.positions)
    root, lengths, theta, info = smooth(measured, ik, PipelineConfig(), covariances=True)  # the smoother's own
    every = uncertainty.model_angle_sd(ik.model, lengths, theta, info["covariance"], stride=1)
    fifth = uncertainty.model_angle_sd(ik.model, lengths, theta, info["covariance"], stride=5)
    # A hinge angle's SD is not smooth where the joint is nearly straight (the end of its domain, 0°): a standing knee
    # there (the simulated Kinect's standing knee reads 4-9° bent, as real ones do) is left out of the comparison.
    # "Nearly straight" is judged on the smoothed state whose covariance is propagated, not on the raw angle: the raw
    # elbow of a squat reads 16-25° where the smoothed one is under 15° (jitter, and since issue 24's decision 4
    # tracking-loss jumps that start at the Kinect's own estimate). Frames where model_angle_sd reads NaN (an angle
    # undefined in a sigma point, as documented; seed 1's hip flexion once) have no SD to compare.
    smoothed = ik.model.positions(root, np.broadcast_to(lengths, (len(theta), len(lengths))), theta)
    smoothed_deg = joint_angles(smoothed)
    for a, name in enumerate(ANGLE_NAMES):
        if name in WELL_DEFINED:
            bent = ~(smoothed_deg[name] < STRAIGHT_DEG) if name.startswith(("knee", "elbow")) else True
            rel = np.abs(fifth[:, a] - every[:, a]) / every[:, a]
            rel = rel[bent & np.isfinite(rel)]
            assert np.median(rel) < 0.03 and np.percentile(rel, 95) < 0.2, f"{name}, seed {seed}"


@pytest.mark.parametrize("seed", SEEDS)
def test_the_pipeline_returns_finite_sds_of_every_angle(seed):
    measured, _, _ = simulate("elbow_flexion", 3, seed=seed)
    result = process(measured)
    assert result.angle_sd is not None
    assert set(result.angle_sd) == set(ANGLE_NAMES)
    for name in WELL_DEFINED:
        sd = result.angle_sd[name]
        assert sd.shape == (measured.n_frames,), name
        assert np.all(np.isfinite(sd)) and np.all(sd >= uncertainty.SD_FLOOR_DEG), f"{name}, seed {seed}"
    assert 0.0 <= result.quality["angle_sd_seconds"] < result.quality["seconds"]


def test_the_online_filter_gives_no_sds():
    measured, _, _ = simulate("elbow_flexion", 1, seed=1)
    assert process(measured, online=True).angle_sd is None
