"""The pipeline: constant segment lengths, gaps filled, accuracy, real recordings, online filter, errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from kinect_agent import skeleton
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.processing.ik import inverse_kinematics
from kinect_agent.processing.online import OnlineFilter
from kinect_agent.processing.pipeline import filter_recording, process, small_pages, smooth
from kinect_agent.recording import Metadata, Recording

from ._data import inject_outliers, smooth_motion, utkinect


def _noisy(rng: np.random.Generator, frames: int, noise: float = 0.015) -> tuple[Recording, np.ndarray, np.ndarray]:
    t, truth, lengths = smooth_motion(frames, rng)
    rec = Recording.from_positions(t, truth + rng.normal(0, noise, truth.shape), Metadata(rate_hz=30.0))
    return rec, truth, lengths


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 2**31 - 1),
    frames=st.integers(12, 40),
    noise=st.floats(0.0, 0.05),
    missing=st.floats(0.0, 0.3),
    smoother=st.sampled_from(["urts", "four_pass"]),
)
def test_segment_lengths_are_constant_after_pass_two(
    seed: int, frames: int, noise: float, missing: float, smoother: str
) -> None:
    rng = np.random.default_rng(seed)
    rec, _, _ = _noisy(rng, frames, noise)
    positions = rec.positions.copy()
    positions[rng.random((frames, skeleton.J)) < missing] = np.nan
    result = process(Recording.from_positions(rec.t, positions), config=PipelineConfig(smoother=smoother))
    lengths = skeleton.bone_lengths(result.filtered.positions)
    np.testing.assert_allclose(lengths, np.tile(result.params.segment_lengths, (frames, 1)), atol=1e-9)


def test_missing_joints_and_frames_are_filled(rng: np.random.Generator) -> None:
    rec, truth, _ = _noisy(rng, 150)
    positions, state = rec.positions.copy(), rec.state.copy()
    positions[40:55] = np.nan  # half a second with no skeleton at all
    positions[:, skeleton.INDEX["WRI_R"]] = np.nan  # a joint never tracked
    positions[100:130, skeleton.INDEX["KNE_L"]] = np.nan
    state[::5, skeleton.INDEX["HEAD"]] = skeleton.INFERRED
    state[~np.all(np.isfinite(positions), axis=-1)] = skeleton.NOT_TRACKED
    gappy = Recording(rec.t, positions, state, Metadata(rate_hz=30.0))
    result = process(gappy)
    out = result.filtered
    assert np.all(np.isfinite(out.positions)), "every joint of every frame must be filled"
    np.testing.assert_array_equal(out.t, rec.t)
    assert np.all(out.state[40:55] == skeleton.INFERRED) and np.all(out.state[:, skeleton.INDEX["WRI_R"]] == 1)
    assert out.state[0, 0] == skeleton.TRACKED
    assert result.quality["frames_without_observation"] == 15
    err = np.linalg.norm(out.positions[40:55] - truth[40:55], axis=-1)
    assert err.mean() < 0.1, f"gap filled {err.mean() * 1000:.0f} mm from the truth"
    assert out.meta.history[-1].startswith("ukf-4pass v1")


@pytest.mark.parametrize("seed", [20261122, 1, 2])  # three draws: a gain on one draw only is no gain
@pytest.mark.parametrize("smoother", ["urts", "four_pass"])
def test_filter_is_closer_to_the_truth_than_the_measurement(seed: int, smoother: str) -> None:
    # White noise of 15 mm per axis: the filter is told that noise model (the defaults are for Kinect's slow jitter).
    rng = np.random.default_rng(seed)
    rec, truth, lengths = _noisy(rng, 200)
    bad, _ = inject_outliers(rec, rng)
    white = PipelineConfig(smoother=smoother, sigma_tracked_m=0.015, offline_q_rot_rad=None, offline_q_root_m=None)
    result = process(bad, config=white)
    raw = np.sqrt(np.mean(np.sum((rec.positions - truth) ** 2, axis=-1)))
    got = np.sqrt(np.mean(np.sum((result.filtered.positions - truth) ** 2, axis=-1)))
    assert got < 0.8 * raw, f"{smoother}: filtered RMSE {got * 1000:.1f} mm vs noise {raw * 1000:.1f} mm"
    assert np.abs(result.params.segment_lengths - lengths).mean() < 0.01


@pytest.mark.parametrize("name", ["joints_s01_e01.txt", "joints_s04_e02.txt"])
def test_real_kinect_recording_comes_out_complete_and_steadier(data_dir: Path, name: str) -> None:
    rec = utkinect(data_dir, name, frames=200)
    result = process(rec)
    assert np.all(np.isfinite(result.filtered.positions))
    before, after = result.quality["segment_sd_before_mm"], result.quality["segment_sd_after_mm"]
    for seg in skeleton.SEGMENT_NAMES:
        assert after[seg] < before[seg], f"{seg}: SD {after[seg]:.2f} mm after vs {before[seg]:.2f} mm before"
    assert set(result.params.joint_angles) >= {"elbow_flexion_L", "knee_flexion_R"}
    angles = result.params.joint_angles["elbow_flexion_L"]
    assert np.all(np.isfinite(angles)) and angles.shape == (200,)


def test_params_rebuild_the_filtered_positions(rng: np.random.Generator) -> None:
    rec, _, _ = _noisy(rng, 60)
    result = process(rec)
    np.testing.assert_allclose(result.params.positions(), result.filtered.positions, atol=1e-9)


def test_progress_reaches_the_total(rng: np.random.Generator) -> None:
    rec, _, _ = _noisy(rng, 100)
    calls: list[tuple[int, int]] = []
    process(rec, progress=lambda done, total: calls.append((done, total)))
    assert calls and calls[-1][0] == calls[-1][1] and all(d <= t for d, t in calls)


def test_online_filter_tracks_frame_by_frame(rng: np.random.Generator) -> None:
    rec, truth, lengths = _noisy(rng, 120)
    filt = OnlineFilter()
    out = np.array([filt.step(float(t), p, s) for t, p, s in zip(rec.t, rec.positions, rec.state, strict=True)])
    assert np.all(np.isfinite(out))
    assert filt.lengths_fixed, "lengths are fixed after the first second"
    err = np.sqrt(np.mean(np.sum((out[60:] - truth[60:]) ** 2, axis=-1)))
    raw = np.sqrt(np.mean(np.sum((rec.positions[60:] - truth[60:]) ** 2, axis=-1)))
    assert err < raw, f"online RMSE {err * 1000:.1f} mm vs noise {raw * 1000:.1f} mm"
    assert filt.kf is not None and filt.kf.lengths is not None
    np.testing.assert_allclose(skeleton.bone_lengths(out[-1]), filt.kf.lengths, atol=1e-9)


def test_online_filter_with_given_lengths_and_bad_input(rng: np.random.Generator) -> None:
    rec, _, lengths = _noisy(rng, 10)
    filt = OnlineFilter(lengths=lengths)
    out = filt.step(0.0, rec.positions[0], rec.state[0])
    np.testing.assert_allclose(skeleton.bone_lengths(out), lengths, atol=1e-9)
    with pytest.raises(ValueError, match="t must increase"):
        filt.step(0.0, rec.positions[1], rec.state[1])
    with pytest.raises(ValueError, match=r"positions must have shape \(20, 3\), got \(19, 3\)"):
        filt.step(1.0, rec.positions[1, :19], rec.state[1])
    with pytest.raises(ValueError, match=r"lengths must have shape \(19,\)"):
        OnlineFilter(lengths=np.ones(3))


def test_process_online_gives_the_same_outputs(rng: np.random.Generator) -> None:
    rec, _, _ = _noisy(rng, 60)
    result = process(rec, online=True)
    assert np.all(np.isfinite(result.filtered.positions)) and result.quality["online"] is True
    np.testing.assert_allclose(result.params.positions(), result.filtered.positions, atol=1e-9)


@pytest.mark.parametrize("online", [False, True])
def test_filter_recording_gives_process_recording_byte_for_byte(rng: np.random.Generator, online: bool) -> None:
    """filter_recording builds neither parameters nor angle SDs (the RTS smooths the means only), and its recording
    and quality are process()'s all the same (seconds and the angle SDs' timings aside)."""
    rec, _, _ = _noisy(rng, 120)
    rec.positions[40:44, 5] += 0.8  # an outlier burst, so that the outlier model removes something
    full, only = process(rec, online=online), filter_recording(rec, online=online)
    for name in ("t", "positions", "state"):
        assert getattr(only.filtered, name).tobytes() == getattr(full.filtered, name).tobytes(), name
    assert only.filtered.meta == full.filtered.meta
    timings = {"seconds", "angle_sd_seconds", "stage_cpu_seconds"}
    assert {k: v for k, v in only.quality.items() if k not in timings} == {
        k: v for k, v in full.quality.items() if k not in timings
    }
    assert full.quality["n_outliers"] > 0 or online
    assert ("angle_sd" in full.quality["stage_cpu_seconds"]) != online
    assert "angle_sd" not in only.quality["stage_cpu_seconds"] and only.quality["angle_sd_seconds"] is None


def test_small_pages_is_a_writable_float64_array() -> None:
    a = small_pages((3, 4, 5))
    a[...] = np.arange(60.0).reshape(3, 4, 5)
    assert a.dtype == np.float64 and a.shape == (3, 4, 5) and a.flags.c_contiguous and a.flags.writeable
    assert a[2, 3, 4] == 59.0
    assert small_pages((0, 36, 36)).shape == (0, 36, 36)


def test_process_refuses_a_recording_without_any_tracked_joint() -> None:
    empty = Recording.from_positions(np.arange(3.0), np.full((3, skeleton.J, 3), np.nan))
    with pytest.raises(ValueError, match="no joint is tracked"):
        process(empty)


@pytest.mark.parametrize("frames", [1, 2, 3])
@pytest.mark.parametrize("online", [False, True])
def test_a_recording_of_one_to_three_frames_is_filtered(rng: np.random.Generator, frames: int, online: bool) -> None:
    rec, _, _ = _noisy(rng, frames)  # one frame once failed in the excursion step: "window shape cannot be larger"
    result = process(rec, online=online)
    assert result.filtered.n_frames == frames
    assert np.all(np.isfinite(result.filtered.positions))


def test_offline_process_noise_overrides_the_shared_one(rng: np.random.Generator) -> None:
    rec, _, _ = _noisy(rng, 40)
    base = dict(sigma_tracked_m=0.03, q_rot_rad=0.1, q_root_m=0.02)
    got = process(rec, config=PipelineConfig(**base, offline_q_rot_rad=0.05, offline_q_root_m=0.005))
    same = process(rec, config=PipelineConfig(**base | dict(q_rot_rad=0.05, q_root_m=0.005), offline_q_rot_rad=None,
                                              offline_q_root_m=None))  # fmt: skip
    np.testing.assert_allclose(got.filtered.positions, same.filtered.positions, atol=1e-12,
                               err_msg="offline_q_* must act as q_* in the offline passes")  # fmt: skip


def test_fixed_innovation_at_mean_acts_on_passes_three_and_four_only(rng: np.random.Generator) -> None:
    rec, _, _ = _noisy(rng, 40)
    sigma_mean = process(rec, config=PipelineConfig(innovation_at_mean=False, fixed_innovation_at_mean=False))
    split = process(rec, config=PipelineConfig(innovation_at_mean=False, fixed_innovation_at_mean=True))
    np.testing.assert_array_equal(split.params.segment_lengths, sigma_mean.params.segment_lengths,
                                  err_msg="passes 1-2 (the lengths) must keep innovation_at_mean")  # fmt: skip
    assert np.abs(split.filtered.positions - sigma_mean.filtered.positions).max() > 1e-6, "passes 3-4 unchanged"
    at_mean = process(rec, config=PipelineConfig(innovation_at_mean=True, fixed_innovation_at_mean=None))
    both = process(rec, config=PipelineConfig(innovation_at_mean=True, fixed_innovation_at_mean=True))
    np.testing.assert_array_equal(both.filtered.positions, at_mean.filtered.positions,
                                  err_msg="None must follow innovation_at_mean")  # fmt: skip


def test_numpy_fallback_gives_the_same_result(rng: np.random.Generator, monkeypatch: pytest.MonkeyPatch) -> None:
    from kinect_agent.body import _fk_numba

    rec, _, _ = _noisy(rng, 40)
    compiled = process(rec).filtered.positions
    monkeypatch.setattr(_fk_numba, "AVAILABLE", False)
    plain = process(rec).filtered.positions
    np.testing.assert_allclose(plain, compiled, atol=1e-8, err_msg="numba kernel and numpy FK disagree")


def test_a_knee_that_outruns_the_random_walk_is_reacquired(rng: np.random.Generator) -> None:
    """A knee bending 145° in 3 frames (UI-PRMD deep squat speed) is gated once, then re-acquired by IK, not lost."""
    from kinect_agent.body import kinematics as km
    from kinect_agent.body.angles import joint_angles
    from kinect_agent.processing.ik import R_FACING

    T = 150
    t = np.arange(T) / 30.0
    theta = np.zeros((T, km.N_THETA))
    bend = np.interp(np.arange(T), [0, 50, 53, 100, 103, T], [0.1, 0.1, 2.6, 2.6, 0.1, 0.1])
    for name in ("KNE_L", "KNE_R"):
        theta[:, km.ROT_START[km.ROT_INDEX[skeleton.INDEX[name]]]] = bend
    model = km.ChainModel()
    model.R_ref[0] = R_FACING
    root = np.broadcast_to([0.0, 0.9, 2.5], (T, 3))
    truth = model.positions(root, np.broadcast_to(km.TYPICAL_LENGTHS, (T, km.N_BONES)), theta)
    rec = Recording.from_positions(t, truth + rng.normal(0.0, 0.01, truth.shape), Metadata(rate_hz=30.0))
    filtered = process(rec, config=PipelineConfig(remove_outliers=False)).filtered
    want = joint_angles(truth)["knee_flexion_L"]
    got = joint_angles(filtered.positions)["knee_flexion_L"]
    settled = np.r_[60:100, 110:T]  # a few frames after each jump
    np.testing.assert_allclose(got[settled], want[settled], atol=10.0, err_msg="knee flexion (deg) after the jumps")


@pytest.mark.parametrize("smoother", ["urts", "four_pass"])
def test_smoother_gives_its_covariance_per_frame_when_asked(rng: np.random.Generator, smoother: str) -> None:
    rec, _, _ = _noisy(rng, 60)
    config = PipelineConfig(smoother=smoother)
    root, lengths, theta, info = smooth(rec, inverse_kinematics(rec.positions), config)
    root_c, lengths_c, theta_c, info_c = smooth(rec, inverse_kinematics(rec.positions), config, covariances=True)
    assert "covariance" not in info
    np.testing.assert_array_equal(root_c, root)  # asking for P changes no estimate
    np.testing.assert_array_equal(theta_c, theta)
    P = info_c["covariance"]
    assert P.shape == (rec.n_frames, 36, 36)
    np.testing.assert_allclose(P, np.swapaxes(P, -1, -2), atol=1e-15)
    assert np.all(np.linalg.eigvalsh(P) > 0), "each frame's covariance is positive definite"
    sd_root = np.sqrt(P[:, np.arange(3), np.arange(3)])
    assert np.all(sd_root < config.p0_root_m), "observed frames know the root better than the start"
