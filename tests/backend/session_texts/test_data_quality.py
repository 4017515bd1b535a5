"""Data quality score, its parts, the outlier heat strip and the segment-length spread."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from backend.session_texts import data_quality
from backend.session_texts.data_quality import (
    LOW_SCORE,
    assess,
    outlier_probabilities,
    outlier_strip,
    part_score,
    quality_score,
    segment_spread_mm,
)
from kinect_agent.analysis.exercise import EXERCISES
from kinect_agent.skeleton import INDEX, NOT_TRACKED
from tests.kinect_agent.analysis._data import noisy, uiprmd

SEEDS = (1, 2, 3)
KNEES = EXERCISES["squat"].defining_angles


def test_part_scores_ramp_between_good_and_bad() -> None:
    assert part_score("tracked_fraction", 1.0) == 100 and part_score("tracked_fraction", 0.5) == 0
    assert part_score("tracked_fraction", 0.79) == pytest.approx(50.0)
    assert part_score("segment_spread_mm", 30.0) == pytest.approx(50.0)
    assert part_score("outlier_fraction", None) is None


def test_score_is_the_weighted_mean_of_the_known_parts() -> None:
    score, parts = quality_score({"tracked_fraction": 1.0, "outlier_fraction": 0.15, "segment_spread_mm": None})
    assert score == round(100 * 0.4 / 0.7) and [p["score"] for p in parts] == [100, 0, None]


def test_score_without_any_part_is_0() -> None:
    assert quality_score({})[0] == 0


def test_segment_spread_of_a_rigid_body_is_0_and_grows_with_noise(rng: np.random.Generator) -> None:
    _, truth = noisy("squat", 2, 1)
    rigid = segment_spread_mm(truth.positions)
    assert max(v for v in rigid.values() if v is not None) < 2.0
    shaken = segment_spread_mm(truth.positions + rng.normal(0, 0.02, truth.positions.shape))
    assert 20 < np.median([v for v in shaken.values() if v is not None]) < 45  # √2 · 20 mm ≈ 28 mm


def test_segment_seen_in_too_few_frames_has_no_spread() -> None:
    _, truth = noisy("squat", 2, 1)
    p = truth.positions.copy()
    p[5:, INDEX["FOO_L"]] = np.nan
    assert segment_spread_mm(p)["FOOT_L"] is None


def test_strip_max_pools_into_at_most_400_columns() -> None:
    t = np.arange(10_000) / 30
    prob = np.zeros((10_000, 20))
    prob[5_000, 3] = 0.99
    prob[:, 7] = np.nan
    strip = outlier_strip(t, prob)
    P = np.array(strip["prob"], dtype=float)
    assert P.shape == (20, len(strip["t_s"])) and P.shape[1] <= 400
    column = int(np.argmax(P[3]))
    assert P[3, column] == 0.99 and abs(strip["t_s"][column] - t[5_000]) <= strip["column_s"]
    assert np.isnan(P[7]).all(), "a joint never seen has no probability"


def test_strip_refuses_times_of_another_length() -> None:
    with pytest.raises(ValueError, match=r"t must have shape \(5,\)"):
        outlier_strip(np.arange(4.0), np.zeros((5, 20)))


@pytest.mark.parametrize("seed", SEEDS)
def test_simulated_session_scores_well_with_every_part_known(seed: int) -> None:
    measured, _ = noisy("squat", 3, seed)
    quality = assess(measured, outlier_probabilities(measured), KNEES, 0.95)
    assert LOW_SCORE < quality["score"] <= 100 and not quality["low"], quality["parts"]
    assert all(p["value"] is not None for p in quality["parts"])


@pytest.mark.parametrize("seed", SEEDS)
def test_losing_the_knees_lowers_the_score(seed: int) -> None:
    measured, _ = noisy("squat", 3, seed)
    good = assess(measured, outlier_probabilities(measured), KNEES, 0.95)["score"]
    state = measured.state.copy()
    lost = np.random.default_rng(seed).random(measured.n_frames) < 0.6
    for joint in ("KNE_L", "KNE_R", "ANK_L", "ANK_R"):
        state[lost, INDEX[joint]] = NOT_TRACKED
    positions = np.where((state == NOT_TRACKED)[..., None], np.nan, measured.positions)
    bad_rec = measured.replace(step="test: knees lost", positions=positions, state=state)
    bad = assess(bad_rec, outlier_probabilities(bad_rec), KNEES, 0.95)
    assert bad["score"] < good - 15 and bad["low"], f"seed {seed}: {good} -> {bad['score']}"


@pytest.mark.parametrize("seed", SEEDS)
def test_outlier_probability_is_nan_where_untracked_and_high_on_a_jump(seed: int) -> None:
    measured, truth = noisy("elbow_flexion", 3, seed)
    rng = np.random.default_rng(seed)
    p = truth.positions + rng.normal(0, 0.01, truth.positions.shape)
    mid = truth.n_frames // 2
    p[mid : mid + 15, INDEX["ELB_L"], 1] += 0.5
    state = truth.state.copy()
    state[:10, INDEX["HEAD"]] = NOT_TRACKED
    p[:10, INDEX["HEAD"]] = np.nan
    rec = truth.replace(step="test", positions=p, state=state)
    prob = data_quality.outlier_probabilities(rec)
    assert np.isnan(prob[:10, INDEX["HEAD"]]).all()
    assert np.mean(prob[mid : mid + 15, INDEX["ELB_L"]] > 0.95) > 0.8, f"seed {seed}"
    assert np.nanmean(np.delete(prob, INDEX["ELB_L"], axis=1) > 0.95) < 0.005, f"seed {seed}"


@pytest.mark.shared_data
@pytest.mark.parametrize("movement", ["m01", "m07"])
def test_uiprmd_recordings_score_high(data_dir: Path, movement: str) -> None:
    rec = uiprmd(data_dir, movement, "s02")
    spec = next(s for s in EXERCISES.values() if s.uiprmd_movement == movement)
    quality = assess(rec, outlier_probabilities(rec), spec.defining_angles, 0.95)
    assert quality["score"] >= 90, quality["parts"]
    spreads = [v for v in quality["segment_spread_mm"].values() if v is not None]
    assert np.median(spreads) < 15 and max(spreads) < 40, quality["segment_spread_mm"]
