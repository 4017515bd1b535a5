"""Tests of bench/real_pairs.py: time/space alignment on synthetic pairs, and one real KERAAL Kinect/Vicon pair."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from bench import real_pairs
from kinect_agent import skeleton
from kinect_agent.body.rotations import axis_rotation
from kinect_agent.evaluation.align import interpolate
from kinect_agent.evaluation.register import robust_kabsch, rotation_deg
from kinect_agent.recording import Recording

ARM = [skeleton.INDEX[j] for j in real_pairs.ARM_JOINTS]


def _motion(t: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Returns (T, J, 3) m: a standing-height cloud of joints, each moving by a sum of random sinusoids."""
    base = rng.uniform([-0.4, -0.8, -0.2], [0.4, 0.8, 0.2], size=(skeleton.J, 3))
    freq = rng.uniform(0.2, 1.5, size=(3, skeleton.J, 3))
    phase = rng.uniform(0.0, 2.0 * np.pi, size=(3, skeleton.J, 3))
    amp = rng.uniform(0.02, 0.15, size=(3, skeleton.J, 3))
    wave = amp[:, None] * np.sin(2.0 * np.pi * freq[:, None] * t[None, :, None, None] + phase[:, None])
    return base + wave.sum(axis=0)


def _synthetic_pair(rng: np.random.Generator, lag_s: float, R0: np.ndarray, t0: np.ndarray,
                    noise_m: float = 0.005) -> tuple[Recording, Recording]:  # fmt: skip
    """Returns (kinect 30 Hz, vicon 60 Hz) with kinect(t) = R0 vicon(t + lag_s) + t0 + noise."""
    t_v = np.arange(0.0, 8.0, 1.0 / 60.0)
    vicon = Recording.from_positions(t_v, _motion(t_v, rng))
    t_k = np.arange(0.0, 6.0, 1.0 / 30.0)
    p_k = interpolate(t_v, vicon.positions, t_k + lag_s) @ R0.T + t0
    return Recording.from_positions(t_k, p_k + rng.normal(0.0, noise_m, p_k.shape)), vicon


def test_align_recovers_an_injected_lag_and_rigid_transform(rng: np.random.Generator) -> None:
    R0 = axis_rotation(1, np.radians(25.0)) @ axis_rotation(0, np.radians(-8.0))
    t0 = np.array([0.1, 0.3, 2.5])
    kinect, vicon = _synthetic_pair(rng, 0.35, R0, t0)
    al = real_pairs.align(kinect, vicon, np.ones(skeleton.J, bool))
    assert abs(al.lag_s - 0.35) <= 1.0 / 60.0, f"lag {al.lag_s:.3f} s, injected 0.35 s"
    assert rotation_deg(al.R.T @ R0) < 0.5, f"rotation error {rotation_deg(al.R.T @ R0):.2f} deg"
    np.testing.assert_allclose(al.t, t0, atol=0.01, err_msg="translation not recovered")


def test_robust_kabsch_ignores_a_few_gross_outliers(rng: np.random.Generator) -> None:
    src = rng.uniform(-1.0, 1.0, size=(400, 3))
    R0, t0 = axis_rotation(2, np.radians(40.0)), np.array([0.5, -0.2, 1.0])
    dst = src @ R0.T + t0 + rng.normal(0.0, 0.003, src.shape)
    dst[:20] += rng.uniform(0.3, 0.8, size=(20, 3))  # 5 % tracking-loss-like errors
    R, t, rms = robust_kabsch(src, dst)
    assert rotation_deg(R.T @ R0) < 0.3
    np.testing.assert_allclose(t, t0, atol=0.005, err_msg="translation pulled by the outliers")
    assert rms < 0.006, f"trimmed RMS {rms:.4f} m"


@pytest.fixture(scope="module")
def keraal_pair() -> dict[str, Any]:
    data = Path(real_pairs.PAIRS_DIR)
    paths = sorted(data.glob("G3-Kinect-CTK-*.txt"))
    if not paths:
        pytest.skip(f"no KERAAL CTK pair in {data}")
    return real_pairs.evaluate_pair(*real_pairs.read_pair(paths[0]), methods=("raw", "pipeline_offline"))


def _arm_median_mm(pair: dict[str, Any], method: str) -> float:
    d = real_pairs.offsets(pair, method)
    arm = [j for j in ARM if pair["good"][j]]
    return 1e3 * float(np.median(d[:, arm]))


def test_registered_raw_kinect_arm_joints_are_near_vicon(data_dir: Path, keraal_pair: dict[str, Any]) -> None:
    assert keraal_pair["alignment"].xcorr > 0.8, "speed cross-correlation too weak for a trustworthy lag"
    assert keraal_pair["overlap"].mean() > 0.9
    median = _arm_median_mm(keraal_pair, "raw")
    assert median < 100.0, f"raw Kinect arm joints {median:.0f} mm from Vicon (median), expected < 100 mm"


def test_pipeline_does_not_move_arm_joints_away_from_vicon(data_dir: Path, keraal_pair: dict[str, Any]) -> None:
    raw, offline = _arm_median_mm(keraal_pair, "raw"), _arm_median_mm(keraal_pair, "pipeline_offline")
    assert offline <= raw + 5.0, f"pipeline offline {offline:.1f} mm vs raw {raw:.1f} mm (median arm offset)"
    d_raw, d_off = (real_pairs.offsets(keraal_pair, m) for m in ("raw", "pipeline_offline"))
    arm = [j for j in ARM if keraal_pair["good"][j]]
    rmse = [1e3 * float(np.sqrt(np.mean(d[:, arm] ** 2))) for d in (d_raw, d_off)]
    assert rmse[1] <= rmse[0] * 1.05, f"pipeline offline arm RMSE {rmse[1]:.1f} mm vs raw {rmse[0]:.1f} mm"
