"""Calibration of the 95 % intervals of range of motion and peak angle on simulated sessions with known truth.

Held-out cases: the constants of kinect_agent.analysis.intervals and kinect_agent.processing.uncertainty were fitted on
views 0° and 60°, seeds 101-110 (bench/uncertainty.py); these use view 30° beside 0° and seeds 201-203, every
simulated exercise they were fitted on.
"""

from __future__ import annotations

import numpy as np
import pytest

from kinect_agent.analysis import intervals, series
from kinect_agent.analysis.exercise import EXERCISES as LIBRARY
from kinect_agent.analysis.range_of_motion import range_of_motion
from kinect_agent.body.angles import ANGLE_NAMES, joint_angles
from kinect_agent.processing.pipeline import process
from kinect_agent.sources.simulator import EXERCISES, simulate

# The motions the interval constants were fitted on. The nine UI-PRMD movements the simulator gained on 2026-11-27 are
# not among them: at 0° deep_squat and side_lunge fall outside FAMILY_RANGE (the others within it); a refit with them
# belongs to issue 24 (with the simulated Kinect's idle knee, which moves these numbers too).
MOTIONS = ("shoulder_abduction", "shoulder_flexion", "elbow_flexion", "seated_knee_extension", "squat", "sit_to_stand",
           "standing_leg_raise", "side_step")  # fmt: skip
assert set(MOTIONS) <= set(EXERCISES)
VIEWS = (0, 30)
SEEDS = (201, 202, 203)
KINDS = ("min_deg", "max_deg", "range_deg")
# Per (motion, view) family the held-out coverage runs 0.921-0.976 (bench/README.md, 2026-11-28: refit with
# SIGMA_GAIN and the defining angles' short tail; before it 0.952-1.000 on the simulator of issue 24).
FAMILY_RANGE = (0.92, 0.995)
# Kinect 1 (intervals.DEVICE_GAIN 4.05, refitted 2026-11-28 on its own views 0°/60°, seeds 501-505): held out
# 0.905-1.000 per family, 0.949 pooled (with 2.15, fitted before that day's refit: 0.865-0.968 and 0.907).
KINECT1_FAMILY_MIN = 0.85


def _hits(motion: str, view: int, seed: int, device: str = "kinect2") -> list[bool]:
    measured, truth, _ = simulate(motion, 5, view_deg=view, seed=seed, device=device)
    result = process(measured)
    smoothed = series.smooth_positions(measured.t, result.filtered.positions)
    est = joint_angles(smoothed)
    yaw = intervals.camera_yaw(smoothed)
    assert yaw is not None and result.angle_sd is not None
    true = range_of_motion(truth.t, joint_angles(series.smooth_positions(truth.t, truth.positions)), presmoothed=True)
    hits = []
    for name in ANGLE_NAMES:
        iv = intervals.angle_intervals(measured.t, est[name], result.angle_sd[name], name, yaw_deg=yaw, device=device,
                                       defining=name in LIBRARY[motion].defining_angles)  # fmt: skip
        ends = true[name]
        if iv is None or ends["range_deg"] is None or ends["range_deg"] >= intervals.MAX_RANGE_DEG:
            continue
        for kind in KINDS:
            end = ends[kind]
            assert end is not None, f"{name}: a true range without its {kind}"
            hits.append(intervals.covers(iv[kind], end, kind))
    return hits


@pytest.fixture(scope="module")
def coverage() -> dict[tuple[str, int], list[bool]]:
    return {(m, v): sum((_hits(m, v, s) for s in SEEDS), []) for m in MOTIONS for v in VIEWS}


def test_the_95_percent_intervals_cover_the_truth_90_to_98_percent_pooled(coverage):
    pooled = np.mean(sum(coverage.values(), []))
    assert 0.90 <= pooled <= 0.98, f"pooled coverage {pooled:.3f} over {MOTIONS} x views {VIEWS} x seeds {SEEDS}"


# The seated knee extension at 0° covered 1.000 after issue 24's idle-knee fix (strict xfail until the refit of
# 2026-11-28, SIGMA_GAIN and the defining angles' short tail: bench/README.md, "Intervals of the moving angles").


@pytest.mark.parametrize("motion", MOTIONS)
@pytest.mark.parametrize("view", VIEWS)
def test_every_motion_and_view_keeps_its_coverage(coverage, motion, view):
    hits = coverage[(motion, view)]
    assert len(hits) >= 60, f"{motion}@{view}: only {len(hits)} intervals"
    rate = float(np.mean(hits))
    lo, hi = FAMILY_RANGE
    assert lo <= rate <= hi, f"{motion}@{view}: coverage {rate:.3f} over seeds {SEEDS}, outside {FAMILY_RANGE}"


@pytest.fixture(scope="module")
def coverage_kinect1() -> dict[tuple[str, int], list[bool]]:
    return {(m, v): sum((_hits(m, v, s, "kinect1") for s in SEEDS), []) for m in MOTIONS for v in VIEWS}


def test_kinect1_intervals_cover_90_to_98_percent_pooled_and_each_family_at_least_85(coverage_kinect1):
    pooled = np.mean(sum(coverage_kinect1.values(), []))
    assert 0.90 <= pooled <= 0.98, f"Kinect 1 pooled coverage {pooled:.3f}"
    low = {f"{m}@{v}": round(float(np.mean(h)), 3) for (m, v), h in coverage_kinect1.items()
           if np.mean(h) < KINECT1_FAMILY_MIN}  # fmt: skip
    assert not low, f"Kinect 1 families under {KINECT1_FAMILY_MIN}: {low}"
