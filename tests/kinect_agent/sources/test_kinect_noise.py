"""Simulated Kinect errors match the paper's tables (Wang et al., section 3.1)."""

from __future__ import annotations

import numpy as np
import pytest

from kinect_agent import skeleton
from kinect_agent.sources import kinect_noise
from kinect_agent.sources.simulator import simulate, simulate_truth


@pytest.fixture(scope="module")
def long_truth():
    """About 4 minutes of standing squats at 30 Hz (the statistic needs many correlation times)."""
    return simulate_truth("squat", 60, seed=3)


@pytest.mark.parametrize("device", kinect_noise.DEVICES)
@pytest.mark.parametrize("pose", kinect_noise.POSES)
@pytest.mark.parametrize("view", kinect_noise.VIEWS)
def test_offset_mean_and_sd_match_table_within_10_percent(long_truth, device, pose, view):
    measured, mask = kinect_noise.add_kinect_noise(
        long_truth, device=device, view_deg=view, pose=pose, rng=np.random.default_rng(11)
    )
    mean, sd = kinect_noise.offset_statistics(measured, long_truth, mask)
    tables = kinect_noise.load_tables()
    key = (device, pose, view)
    names = ", ".join(skeleton.JOINTS)
    np.testing.assert_allclose(mean, tables.offset_mean[key], rtol=0.10, err_msg=f"mean offset {key} ({names})")
    np.testing.assert_allclose(sd, tables.offset_sd[key], rtol=0.10, err_msg=f"offset SD {key} ({names})")


@pytest.mark.parametrize(("device", "pose", "view"), [("kinect1", "standing", 0), ("kinect2", "sitting", 60)])
def test_outlier_removal_gain_is_of_the_papers_order(long_truth, device, pose, view):
    measured, mask = kinect_noise.add_kinect_noise(
        long_truth, device=device, view_deg=view, pose=pose, rng=np.random.default_rng(12)
    )
    d = np.linalg.norm(measured.positions - long_truth.positions, axis=-1)
    tracked = measured.state == skeleton.TRACKED
    with_outliers = np.where(tracked, d, np.nan)
    without = np.where(tracked & ~mask, d, np.nan)
    mean_gain = 100 * (1 - np.nanmean(without) / np.nanmean(with_outliers))
    sd_gain = 100 * np.mean(1 - np.nanstd(without, axis=0) / np.nanstd(with_outliers, axis=0))
    paper_mean, paper_sd = kinect_noise.load_tables().gain_pct[device, pose, view]
    assert 1.0 <= mean_gain <= 12.0, f"mean gain {mean_gain:.1f} % (paper {paper_mean} %)"
    assert 15.0 <= sd_gain <= 60.0, f"SD gain {sd_gain:.1f} % (paper {paper_sd} %)"


def test_outlier_mask_marks_exactly_the_replaced_joint_frames():
    truth = simulate_truth("shoulder_abduction", 8, seed=4)
    measured, mask = kinect_noise.add_kinect_noise(
        truth, device="kinect1", view_deg=60, pose="standing", rng=np.random.default_rng(21)
    )
    # The Gaussian component is drawn first from the generator, so the same seed rebuilds it exactly.
    tables, key = kinect_noise.load_tables(), ("kinect1", "standing", 60)
    mu, sigma = kinect_noise.folded_normal_parameters(tables.offset_mean[key], tables.offset_sd[key])
    dt = float(np.median(np.diff(truth.t)))  # as add_kinect_noise computes it
    model = truth.positions + kinect_noise.gaussian_offsets(
        truth.positions, mu, sigma, tables.bone_mean[key], tables.bone_sd[key], np.random.default_rng(21), dt
    )
    tracked = measured.state == skeleton.TRACKED
    assert mask.any(), "a 60° Kinect 1 session has tracking loss"
    assert np.all(measured.state[mask] == skeleton.TRACKED), "outliers keep the TRACKED state, as the SDK does"
    same = np.all(measured.positions == model, axis=-1)
    np.testing.assert_array_equal(same[tracked], ~mask[tracked], err_msg="replaced joint-frames differ from the mask")


def test_offset_distance_is_the_folded_normal_whatever_the_direction(rng):
    truth = simulate_truth("squat", 3, seed=1)
    mu, sigma = np.full(skeleton.J, 0.1), np.full(skeleton.J, 0.02)
    off = kinect_noise.gaussian_offsets(truth.positions, mu, sigma, np.zeros(14), np.zeros(14), rng, 1 / 30)
    d = np.linalg.norm(off, axis=-1)
    assert np.all(np.isfinite(d)) and d.min() >= 0.0
    np.testing.assert_allclose(d.mean(), 0.1, rtol=0.1)


def test_states_and_nan_agree_and_lost_frames_exist():
    measured, _, mask = simulate("side_step", 10, device="kinect2", view_deg=30, seed=5)
    lost = measured.state == skeleton.NOT_TRACKED
    assert lost.any() and (measured.state == skeleton.INFERRED).any()
    assert np.all(np.isnan(measured.positions[lost]))
    assert not np.any(mask & lost)
    assert np.all(np.isfinite(measured.positions[~lost]))


def test_jitter_is_temporally_correlated():
    z = kinect_noise.ar1(np.random.default_rng(1), 20_000, 2, 1 / 30)
    lag1 = np.mean(z[1:] * z[:-1]) / np.mean(z * z)
    np.testing.assert_allclose(lag1, np.exp(-1 / 30 / kinect_noise.TAU_S), atol=0.02)
    np.testing.assert_allclose(z.std(), 1.0, atol=0.05)


def test_bad_settings_are_refused(long_truth):
    rng = np.random.default_rng(0)
    with pytest.raises(kinect_noise.SimulationError, match="view 45"):
        kinect_noise.add_kinect_noise(long_truth, device="kinect2", view_deg=45, pose="standing", rng=rng)
    with pytest.raises(kinect_noise.SimulationError, match="unknown device"):
        kinect_noise.add_kinect_noise(long_truth, device="kinect3", view_deg=0, pose="standing", rng=rng)


@pytest.mark.parametrize(("device", "pose", "view"), [("kinect1", "sitting", 0), ("kinect2", "standing", 60)])
def test_bone_length_errors_are_of_the_tabled_size(long_truth, device, pose, view):
    measured, mask = kinect_noise.add_kinect_noise(
        long_truth, device=device, view_deg=view, pose=pose, rng=np.random.default_rng(13)
    )
    mean, sd = kinect_noise.bone_length_error(measured, long_truth, mask)
    tables, key = kinect_noise.load_tables(), (device, pose, view)
    error_mm = np.abs(mean - tables.bone_mean[key]) * 1000
    ratio = sd / tables.bone_sd[key]
    # Typical segments match; single segments may miss (see kinect_noise: the distance law comes first).
    assert np.median(error_mm) < 25.0, f"segment mean error vs table, mm: {np.round(error_mm)}"
    assert 0.8 < np.median(ratio) < 1.6, f"segment SD / table: {np.round(ratio, 2)}"


@pytest.mark.parametrize(("device", "pose", "view"), [("kinect2", "standing", 0), ("kinect1", "sitting", 30)])
def test_outlier_law_reproduces_the_papers_gains_in_expectation(device, pose, view):
    """A large Monte Carlo sample of the mixture (folded-normal clean distance, outliers = clean offset + a jump of
    random direction) gives the tabled SD gain per joint and the mean gain wherever the law is not capped."""
    tables, key = kinect_noise.load_tables(), (device, pose, view)
    mean, sd = tables.offset_mean[key], tables.offset_sd[key]
    p, jump = kinect_noise.outlier_law(mean, sd, *tables.gain_pct[key])
    mu, sigma = kinect_noise.folded_normal_parameters(mean, sd)
    rng, n, h = np.random.default_rng(5), 400_000, kinect_noise.OUTLIER_HALF_WIDTH
    clean = np.abs(mu + sigma * rng.standard_normal((n, skeleton.J)))  # (n, J) m
    u = rng.standard_normal((n, skeleton.J, 3))
    u /= np.linalg.norm(u, axis=-1, keepdims=True)
    length = jump * (1.0 + h * (2.0 * rng.random((n, skeleton.J)) - 1.0))
    offset = clean[..., None] * np.array([1.0, 0.0, 0.0])  # the direction of the clean offset does not matter
    lost = rng.random((n, skeleton.J)) < p
    d = np.where(lost, np.linalg.norm(offset + length[..., None] * u, axis=-1), clean)
    kept = np.where(lost, np.nan, d)
    mean_gain = 100 * (1 - np.nanmean(kept, axis=0) / d.mean(axis=0))
    sd_gain = 100 * (1 - np.nanstd(kept, axis=0) / d.std(axis=0))
    paper_mean, paper_sd = tables.gain_pct[key]
    free = p < kinect_noise.OUTLIER_FRACTION_MAX  # a capped fraction reaches the SD gain but not the mean gain
    assert free.sum() >= 12, f"fractions {p}"
    np.testing.assert_allclose(mean_gain[free], paper_mean, rtol=0.06, err_msg="mean gain per joint")
    assert np.all(mean_gain[~free] < paper_mean + 0.5), f"capped joints' mean gains {mean_gain[~free]}"
    np.testing.assert_allclose(sd_gain, paper_sd, rtol=0.04, err_msg="SD gain per joint")
    assert np.all((p > 0.001) & (p <= 0.1)) and np.all(jump > 2 * sd), f"fractions {p}, jumps {jump} m"


def test_jump_moments_match_a_monte_carlo_of_the_jump():
    """E|o + R·u| − mean and E[(|o + R·u| − mean)²] as jump_moments computes them (quadrature), against sampling."""
    mean, sd, jump = np.array([0.256, 0.085, 0.04]), np.array([0.02, 0.05, 0.03]), np.array([[0.1], [0.5], [0.02]])
    e, v = kinect_noise.jump_moments(mean, sd, jump)
    mu, sigma = kinect_noise.folded_normal_parameters(mean, sd)
    rng, n = np.random.default_rng(8), 1_000_000
    a = np.abs(mu + sigma * rng.standard_normal((n, 3)))
    u = rng.standard_normal((n, 3, 3))
    u /= np.linalg.norm(u, axis=-1, keepdims=True)
    r = jump[:, 0] * (1.0 + kinect_noise.OUTLIER_HALF_WIDTH * (2.0 * rng.random((n, 3)) - 1.0))
    d = np.linalg.norm(a[..., None] * np.array([0.0, 0.0, 1.0]) + r[..., None] * u, axis=-1)
    np.testing.assert_allclose(e[:, 0], d.mean(axis=0) - mean, rtol=0.01, atol=2e-5)
    np.testing.assert_allclose(v[:, 0], ((d - mean) ** 2).mean(axis=0), rtol=0.01)


def test_a_tracking_loss_jump_starts_at_the_kinects_biased_estimate_not_at_the_truth():
    """Outliers are the Gaussian measurement (truth + its biased offset) plus a jump of random direction: averaged
    over many outliers of one joint, the jump vanishes and their mean lands on the biased estimate, not on the
    truth; each outlier lies within the jump's law (jump·[1 − h, 1 + h]) of the biased estimate."""
    truth = simulate_truth("squat", 40, seed=2)
    device, view, pose = "kinect1", 60, "standing"
    measured, mask = kinect_noise.add_kinect_noise(
        truth, device=device, view_deg=view, pose=pose, rng=np.random.default_rng(31)
    )
    tables, key = kinect_noise.load_tables(), (device, pose, view)
    mu, sigma = kinect_noise.folded_normal_parameters(tables.offset_mean[key], tables.offset_sd[key])
    dt = float(np.median(np.diff(truth.t)))
    biased = truth.positions + kinect_noise.gaussian_offsets(
        truth.positions, mu, sigma, tables.bone_mean[key], tables.bone_sd[key], np.random.default_rng(31), dt
    )  # the same draws as add_kinect_noise's Gaussian component
    _, jump = kinect_noise.setting_outlier_law(device, pose, view)
    h = kinect_noise.OUTLIER_HALF_WIDTH
    frames, joints = np.nonzero(mask)
    length = np.linalg.norm(measured.positions[mask] - biased[mask], axis=-1)
    assert np.all(length >= jump[joints] * (1 - h) - 1e-9) and np.all(length <= jump[joints] * (1 + h) + 1e-9)
    root = skeleton.INDEX["HIP_L"]  # a large, steady Kinect 1 offset (≈ 0.2 m) and many outliers
    sel = joints == root
    assert sel.sum() > 500
    from_biased = np.linalg.norm((measured.positions[mask] - biased[mask])[sel].mean(axis=0))
    from_truth = np.linalg.norm((measured.positions[mask] - truth.positions[mask])[sel].mean(axis=0))
    offset = np.linalg.norm((biased - truth.positions)[mask][sel].mean(axis=0))
    assert offset > 0.1, f"HIP_L's mean offset {offset:.3f} m"
    assert from_biased < 0.25 * offset, f"outliers' mean {from_biased:.3f} m from the biased estimate"
    np.testing.assert_allclose(from_truth, offset, rtol=0.25, err_msg="outliers' mean sits at the Kinect's offset")


def test_exact_bursts_cover_the_asked_fraction():
    fraction = np.array([0.0, 0.01, 0.03, 0.08])
    hit = kinect_noise._exact_bursts(np.random.default_rng(3), 6000, fraction, 30.0)
    np.testing.assert_allclose(hit.mean(axis=0), fraction, atol=0.004, err_msg="covered fraction per joint")
