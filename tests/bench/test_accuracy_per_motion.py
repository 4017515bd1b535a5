"""bench/accuracy.py per motion (issue 13): one short motion per source (CMU 13_29's first 12 s, an HDM05 squat clip,
a UI-PRMD Vicon deep-squat episode) seen by a simulated Kinect 2 at 0° and 60°, on three seeds; the offline pipeline
must meet, on every seed separately, the targets that hold there.

Not asserted, because they do not hold (bench/README.md, "Per-motion accuracy (issue 13)"): random part ≤ ½ raw's
(the Kinect's clean error is too slow for any filter that follows the motion: even perfect outlier removal plus an
ideal 2 Hz low-pass of the error stays above it), and the elbow/knee target on CMU's 12 s, the HDM05 squat at 0° and
UI-PRMD m01 at 60° (off by 0.1-2.6° on one to three seeds).
"""

import copy
from typing import Any

import pytest

from bench import accuracy

SEEDS = (1, 2, 3)  # never one seed: a gain that holds on one draw only is no gain
# Rows where the offline pipeline's position RMSE is not below a baseline's, measured, with the most it may lose by
# (mm). Since the simulated Kinect's idle knee was recalibrated to real standing knees (2026-11-27, bench/README.md
# "Counts on new sessions of the same people, the live deep squat, the idle knee"), seed 2 of the short HDM05 squat
# at 60° loses to CV Kalman + RTS by 1.8 mm (134.0 vs 132.2; it won by 0.16 mm before) and UI-PRMD m01 at 0° ties
# it (105.7 mm both). Issue 24's white-noise and bias work is where they are to be won back; any other loss fails.
# Since the simulator's tracking-loss jumps start at the Kinect's own estimate (issue 24 decision 4, 2026-11-28) that
# squat seed loses by 3.7 mm (137.6 vs 133.9): on its 35 frames the shorter jumps are flagged with recall 0.77 instead
# of 1.00 (the whole motion, 24 clips, still wins by 6.8 mm on that seed; bench/README.md, decision 4).
KNOWN_LOSSES = {("hdm05_squat1Reps", 60, 2, "cv_kalman_rts"): 4.2, ("ui_prmd_m01", 0, 2, "cv_kalman_rts"): 0.2}


Rows = dict[tuple[str, int, int], dict[str, Any]]


@pytest.fixture(scope="module")
def rows(quick_accuracy: dict[str, Any]) -> Rows:
    """{(motion, view, seed): bench/accuracy.py's result row}: the quick motions, every view and seed, with the default
    PipelineConfig: the rows of the quick run's results file (tests/bench/conftest.py), which computes exactly these
    (accuracy.run_motions over motions(quick=True), MOTION_VIEWS and the default seeds)."""
    motions = quick_accuracy["motions"]
    assert quick_accuracy["config_overrides"] == [] and motions["device"] == accuracy.MOTION_DEVICE
    assert tuple(motions["seeds"]) == SEEDS and tuple(motions["views_deg"]) == accuracy.MOTION_VIEWS
    out = {(r["motion"], r["view_deg"], r["seed"]): copy.deepcopy(r) for r in motions["rows"]}
    expected = {(m.name, v, s) for m in accuracy.motions(quick=True) for v in accuracy.MOTION_VIEWS for s in SEEDS}
    assert set(out) == expected, sorted(set(out) ^ expected)
    return out


@pytest.mark.shared_data
def test_one_motion_per_source(rows: Rows) -> None:
    sources = {row["source"] for row in rows.values()}
    assert sources == {"cmu", "hdm05", "ui_prmd_vicon"}, sources
    for (motion, view, seed), row in rows.items():
        for name in accuracy.MOTION_METHODS:
            m = row["methods"][name]
            assert abs(m["random_mm"] ** 2 + m["bias_mm"] ** 2 - m["rmse_mm"] ** 2) < 1e-6 * m["rmse_mm"] ** 2, (
                f"{motion} {view}° seed {seed} {name}: random² + bias² must equal RMSE², {m}"
            )


@pytest.mark.shared_data
@pytest.mark.parametrize("baseline", ["cv_kalman_rts", "one_euro"])
def test_offline_position_rmse_is_below_the_baseline(rows: Rows, baseline: str) -> None:
    losses = {}
    for (motion, view, seed), row in rows.items():
        off, base = row["methods"]["pipeline_offline"]["rmse_mm"], row["methods"][baseline]["rmse_mm"]
        if off >= base:
            losses[motion, view, seed, baseline] = off - base
    unknown = {k: f"+{v:.2f} mm" for k, v in losses.items() if k not in KNOWN_LOSSES}
    grown = {k: f"+{v:.2f} mm" for k, v in losses.items() if k in KNOWN_LOSSES and v > KNOWN_LOSSES[k]}
    assert not unknown and not grown, (unknown, grown)


@pytest.mark.shared_data
@pytest.mark.parametrize("baseline", ["cv_kalman_rts", "one_euro"])
def test_offline_random_part_is_below_the_baseline(rows: Rows, baseline: str) -> None:
    for (motion, view, seed), row in rows.items():
        off, base = row["methods"]["pipeline_offline"]["random_mm"], row["methods"][baseline]["random_mm"]
        assert off < base, f"{motion} {view}° seed {seed}: offline random part {off:.1f} mm vs {baseline} {base:.1f} mm"


@pytest.mark.shared_data
@pytest.mark.parametrize(("motion", "view"), [("ui_prmd_m01", 0), ("hdm05_squat1Reps", 60)])
@pytest.mark.parametrize("baseline", ["cv_kalman_rts", "one_euro"])
def test_offline_elbow_knee_rmse_is_below_the_baseline(rows: Rows, motion: str, view: int, baseline: str) -> None:
    for seed in SEEDS:
        m = rows[motion, view, seed]["methods"]
        off, base = m["pipeline_offline"]["angle_rmse_deg"], m[baseline]["angle_rmse_deg"]
        assert off < base, f"{motion} {view}° seed {seed}: offline elbow/knee {off:.2f}° vs {baseline} {base:.2f}°"


# Issue 24's restated targets, judged per seed by bench/accuracy.py (ISSUE24_TARGETS): the random part within 5 mm
# of the ideal 2 Hz low-pass of the clean error, the elbow/knee RMSE within 1° of perfect outlier removal. On these
# short clips they miss in the rows below, measured 2026-11-28 (bench/README.md "Issue 24's restated targets per
# motion, view and seed"), with the most each may miss by (measured margin, rounded up, + 0.5): CMU's 12 s at both
# views on every seed (the fast arm and leg swings the random walk of the angles rounds off), and the 1.2-1.9 s HDM05
# and UI-PRMD clips on some seeds. Any other miss, or a known one grown, fails. Re-measured on 2026-11-28 after the
# simulator's outliers moved to the Kinect's biased estimate (decision 4): the HDM05 squat clip misses the random-part
# target by more (0° seed 1 +1.16, 60° seed 1 +0.16, new; 60° seed 2 +7.52: the short jumps it flags less often) and
# CMU 60° the angle target (seed 2 +1.16, seed 3 +3.12); the others as before.
KNOWN_MISSES = {
    "random<=oracle_lowpass_2hz+5": {
        ("cmu_13_29", 0, 1): 2.4, ("cmu_13_29", 0, 2): 2.9, ("cmu_13_29", 0, 3): 2.2, ("cmu_13_29", 60, 1): 2.2,
        ("cmu_13_29", 60, 2): 4.1, ("cmu_13_29", 60, 3): 2.3, ("hdm05_squat1Reps", 0, 1): 1.7,
        ("hdm05_squat1Reps", 0, 3): 4.0, ("hdm05_squat1Reps", 60, 1): 0.7, ("hdm05_squat1Reps", 60, 2): 8.1,
        ("ui_prmd_m01", 0, 2): 2.1, ("ui_prmd_m01", 60, 1): 3.5, ("ui_prmd_m01", 60, 2): 2.6,
        ("ui_prmd_m01", 60, 3): 8.8,
    },
    "angle<=oracle_clean+1": {
        ("cmu_13_29", 0, 1): 2.1, ("cmu_13_29", 0, 2): 2.7, ("cmu_13_29", 0, 3): 1.7, ("cmu_13_29", 60, 1): 1.2,
        ("cmu_13_29", 60, 2): 1.7, ("cmu_13_29", 60, 3): 3.7, ("hdm05_squat1Reps", 0, 3): 1.5,
        ("ui_prmd_m01", 0, 3): 1.0, ("ui_prmd_m01", 60, 3): 0.8,
    },
}  # fmt: skip


@pytest.mark.shared_data
@pytest.mark.parametrize("target", sorted(KNOWN_MISSES))
def test_issue24_targets_miss_only_where_measured(rows: Rows, target: str) -> None:
    known = KNOWN_MISSES[target]
    misses = {}
    for key, row in rows.items():
        t = row["targets"][target]
        if not t["pass"]:
            misses[key] = t["margin"]
    unknown = {k: f"+{v:.2f}" for k, v in misses.items() if k not in known}
    grown = {k: f"+{v:.2f} > {known[k]}" for k, v in misses.items() if k in known and v > known[k]}
    assert not unknown and not grown, (unknown, grown)
