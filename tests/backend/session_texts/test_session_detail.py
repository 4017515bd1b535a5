"""Session page evidence: min/max decimation, angle curves, repetition peak speeds, hand paths."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from backend.session_texts.session_detail import (
    MAX_CURVE_POINTS,
    angle_curves,
    angle_label,
    angular_speeds,
    curve,
    hand_paths,
    is_arm_exercise,
    measured_angles,
    minmax_indices,
    peak_speeds,
)
from kinect_agent.analysis.document import RepetitionItem
from kinect_agent.analysis.exercise import EXERCISES
from kinect_agent.analysis.report import analyze_recording
from kinect_agent.body.angles import DOMAIN_DEG
from tests.kinect_agent.analysis._data import noisy, uiprmd

SEEDS = (1, 2, 3)


def test_minmax_keeps_every_sample_of_a_short_series() -> None:
    np.testing.assert_array_equal(minmax_indices(np.arange(10.0), 20), np.arange(10))


@pytest.mark.parametrize("seed", SEEDS)
def test_minmax_keeps_the_extremes_and_at_most_max_points(seed: int) -> None:
    y = np.random.default_rng(seed).normal(size=20_000).cumsum()
    idx = minmax_indices(y, 1500)
    assert idx.size <= 1500 and np.all(np.diff(idx) > 0)
    assert y[idx].max() == y.max() and y[idx].min() == y.min(), f"seed {seed}"


def test_minmax_keeps_a_gap_as_a_gap() -> None:
    y = np.sin(np.linspace(0, 20, 9000))
    y[3000:4500] = np.nan
    idx = minmax_indices(y, 300)
    assert np.isnan(y[idx]).any() and np.isfinite(y[idx]).sum() > 200


def test_minmax_refuses_a_2d_series() -> None:
    with pytest.raises(ValueError, match=r"shape \(T,\)"):
        minmax_indices(np.zeros((3, 2)))


def test_curve_rounds_and_sends_nan_as_none() -> None:
    out = curve(np.array([0.0, 0.0333, 0.0667]), np.array([1.234, np.nan, 3.0]))
    assert out == {"t_s": [0.0, 0.033, 0.067], "deg": [1.2, None, 3.0]}


@pytest.mark.parametrize("seed", SEEDS)
def test_curves_of_an_arm_held_overhead_stay_in_the_domain_without_a_turn(seed: int) -> None:
    measured, truth = noisy("shoulder_flexion", 3, seed)
    names = ("shoulder_flexion_L", "shoulder_flexion_R")
    measured_deg = measured_angles(truth.t, truth.positions, names)
    curves = angle_curves(measured.t, measured.positions, measured_deg, names)
    for c in curves:
        deg = np.array(c["deg"], dtype=float)
        deg = deg[np.isfinite(deg)]
        lo, hi = DOMAIN_DEG[c["angle"]]
        assert deg.size and np.all((deg >= lo) & (deg < hi)), f"seed {seed}: {c['label']} leaves [{lo}, {hi})"
    moving = np.array(curves[1]["deg"], dtype=float)  # the filtered curve of the moving (left) arm
    assert np.nanmax(moving) > 150 and np.nanmax(np.abs(np.diff(moving))) < 30, f"seed {seed}: no jump overhead"


def test_angle_label_is_in_words() -> None:
    assert angle_label("knee_flexion_R") == "right knee flexion"
    assert angle_label("trunk_flexion") == "trunk flexion"


@pytest.mark.parametrize("seed", SEEDS)
def test_filtered_curve_follows_the_truth_and_raw_one_is_noisier(seed: int) -> None:
    measured, truth = noisy("squat", 3, seed)
    names = EXERCISES["squat"].defining_angles
    truth_deg = measured_angles(truth.t, truth.positions, names)
    curves = angle_curves(measured.t, measured.positions, truth_deg, names)
    raw, filtered = curves[0], curves[1]
    assert (raw["kind"], filtered["kind"]) == ("raw", "filtered")
    assert len(filtered["t_s"]) == measured.n_frames  # shorter than MAX_CURVE_POINTS: every frame
    raw_deg = np.array(raw["deg"], dtype=float)
    seen = np.isfinite(raw_deg)
    corr = np.corrcoef(raw_deg[seen], truth_deg[names[0]][seen])[0, 1]
    assert corr > 0.6, f"seed {seed}: the raw curve follows the movement (r = {corr:.2f})"
    assert filtered["deg"] == curve(truth.t - truth.t[0], truth_deg[names[0]])["deg"]
    assert np.nanstd(np.diff(np.array(raw["deg"], dtype=float))) > np.std(np.diff(filtered["deg"])), f"seed {seed}"


def _rep(start_s: float, end_s: float, side: str) -> RepetitionItem:
    """A repetition as the analysis lists it; only its times and side matter to the peak speed."""
    return RepetitionItem(index=0, start_s=start_s, end_s=end_s, duration_s=end_s - start_s, amplitude_deg=0.0,
                          peak_deg=0.0, side=side, peak_s=None, withheld=None)  # fmt: skip


def _known(speeds: list[float | None]) -> list[float]:
    """Returns peak speeds that are all known (each repetition here moves its angle)."""
    known = [s for s in speeds if s is not None]
    assert len(known) == len(speeds), speeds
    return known


@pytest.mark.parametrize("seed", SEEDS)
def test_peak_speeds_are_those_of_a_known_sine(seed: int) -> None:
    rng = np.random.default_rng(seed)
    period, amplitude = rng.uniform(2.0, 4.0), rng.uniform(30.0, 80.0)
    t = np.arange(0, 3 * period, 1 / 30)
    angle = amplitude / 2 * (1 - np.cos(2 * np.pi * t / period))
    reps = [_rep(k * period, (k + 1) * period, "left") for k in range(3)]
    speeds = _known(peak_speeds(t, angular_speeds(t, {"knee_flexion_L": angle}), reps))
    expected = np.pi * amplitude / period
    np.testing.assert_allclose(speeds, expected, rtol=0.05, err_msg=f"seed {seed}")


def test_peak_speed_of_a_side_reads_that_side_only() -> None:
    t = np.arange(0, 4, 1 / 30)
    still, moving = np.zeros_like(t), 40 * np.sin(np.pi * t / 4)
    speeds = angular_speeds(t, {"knee_flexion_L": still, "knee_flexion_R": moving})
    left, right, both = _known(peak_speeds(t, speeds, [_rep(0.0, 4.0, s) for s in ("left", "right", "both")]))
    assert left == pytest.approx(0.0, abs=0.1) and right == both > 20


@pytest.mark.parametrize("seed", SEEDS)
def test_peak_speeds_of_simulated_repetitions_are_positive(seed: int) -> None:
    measured, truth = noisy("squat", 3, seed)
    spec = EXERCISES["squat"]
    doc = analyze_recording(measured, spec, filtered=truth)
    angles = measured_angles(truth.t, truth.positions, spec.defining_angles)
    speeds = _known(peak_speeds(truth.t, angular_speeds(truth.t, angles), doc.repetition_list))
    assert len(speeds) == 3 and all(20 < s < 400 for s in speeds), f"seed {seed}: {speeds}"


def test_arm_exercises_are_the_shoulder_and_elbow_ones() -> None:
    assert is_arm_exercise(EXERCISES["shoulder_abduction"].defining_angles)
    assert is_arm_exercise(EXERCISES["elbow_flexion"].defining_angles)
    assert not is_arm_exercise(EXERCISES["squat"].defining_angles)


@pytest.mark.parametrize("seed", SEEDS)
def test_hand_path_of_abduction_rises_sideways_within_one_arm_length(seed: int) -> None:
    _, truth = noisy("shoulder_abduction", 3, seed)
    paths = hand_paths(truth.positions, truth.t)
    for side in ("left", "right"):
        path = paths[side]
        assert path is not None, f"seed {seed}: no {side} hand path"
        out, up, fwd = (np.array(path[k]) for k in ("outward", "up", "forward"))
        assert len(out) <= 600
        assert up.min() < -0.8 and up.max() > 0.5, f"seed {seed} {side}: the hand hangs, then rises"
        assert np.all(np.sqrt(out**2 + up**2 + fwd**2) < 1.05), f"seed {seed} {side}"
        assert np.median(out[up > 0.3]) > np.median(np.abs(fwd[up > 0.3])), f"seed {seed} {side}: sideways"


@pytest.mark.shared_data
def test_uiprmd_shoulder_abduction_curves_and_speeds(data_dir: Path) -> None:
    rec = uiprmd(data_dir, "m07", "s02")
    spec = EXERCISES["standing_shoulder_abduction"]
    doc = analyze_recording(rec, spec)
    angles = measured_angles(rec.t, rec.positions, spec.defining_angles)
    curves = angle_curves(rec.t, rec.positions, angles, spec.defining_angles, "smoothed")
    right = next(c for c in curves if c["angle"] == "shoulder_abduction_R" and c["kind"] == "smoothed")
    assert len(right["t_s"]) <= MAX_CURVE_POINTS and max(right["deg"]) > 60, "the right arm is raised sideways"
    speeds = _known(peak_speeds(rec.t, angular_speeds(rec.t, angles), doc.repetition_list))
    assert len(speeds) == 10 and all(30 < s < 600 for s in speeds), speeds
    paths = hand_paths(rec.positions, rec.t)
    right_path, left_path = paths["right"], paths["left"]
    assert right_path is not None and left_path is not None, paths.keys()
    assert max(right_path["up"]) > max(left_path["up"]) + 0.3, "only the right hand rises"
