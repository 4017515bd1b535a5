"""The interval arithmetic of kinect_agent.analysis.intervals on simple series, and the repetition count's interval."""

from __future__ import annotations

import numpy as np
import pytest

from backend.i18n import translator
from backend.session_texts import reasons
from kinect_agent.analysis import intervals, series
from kinect_agent.analysis.angles import counting_angles
from kinect_agent.analysis.exercise import EXERCISES
from kinect_agent.analysis.reasons import Reason
from kinect_agent.body.angles import joint_angles
from kinect_agent.processing.pipeline import process
from kinect_agent.sources.simulator import simulate

SEEDS = (1, 2, 3)


def _sine(seed: int) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(600) / 30.0
    rng = np.random.default_rng(seed)
    return t, 60.0 + 40.0 * np.sin(2 * np.pi * t / 4.0 + rng.uniform(0, 6))


def _expected_b(x: np.ndarray, name: str, yaw_deg: float) -> tuple[float, float, float]:
    """b of (min_deg, max_deg, range_deg) from the model's formula, the tails taken from the series' percentiles."""
    p1, p10, p90, p99 = np.percentile(x, [1, 10, 90, 99])
    tails = (p10 - p1, p99 - p90, np.hypot(p10 - p1, p99 - p90))
    gain = 1.0 + intervals.YAW_GAIN * np.sin(np.radians(yaw_deg))
    B = intervals.SYSTEMATIC_DEG[name]
    return tuple(gain * np.hypot(b, k * tau) for b, k, tau in zip(B, intervals.TAIL_GAIN, tails, strict=True))


def _intervals(
    t: np.ndarray, x: np.ndarray, sd: np.ndarray, name: str, *, yaw_deg: float, device: str = "kinect2"
) -> dict[str, list[float]]:
    """Returns intervals.angle_intervals of an angle that has them."""
    iv = intervals.angle_intervals(t, x, sd, name, yaw_deg=yaw_deg, device=device)
    assert iv is not None, name
    return iv


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("yaw", (0.0, 30.0, 60.0))
def test_widths_follow_the_per_frame_sd_and_the_systematic_part(seed, yaw):
    t, x = _sine(seed)
    x = x - 60.0  # ±40°, inside the angle's domain (±90°)
    sd = np.full_like(t, 2.0)
    name = "trunk_lateral_flexion"  # the one angle with a B (intervals.SYSTEMATIC_DEG)
    iv = _intervals(t, x, sd, name, yaw_deg=yaw)
    b_min, b_max, b_range = _expected_b(x, name, yaw)
    lo, hi = np.percentile(x, [1, 99])
    msg = f"seed {seed}, yaw {yaw}"
    s = intervals.SIGMA_GAIN * 2.0  # the share of the per-frame SD the intervals keep
    np.testing.assert_allclose(np.mean(iv["min_deg"]), lo, atol=0.1, err_msg=msg)
    np.testing.assert_allclose(np.diff(iv["min_deg"])[0], 2 * 1.96 * np.hypot(s, b_min), atol=0.2, err_msg=msg)
    np.testing.assert_allclose(np.diff(iv["max_deg"])[0], 2 * 1.96 * np.hypot(s, b_max), atol=0.2, err_msg=msg)
    np.testing.assert_allclose(np.diff(iv["range_deg"])[0], 2 * 1.96 * np.sqrt(2 * s**2 + b_range**2), atol=0.2,
                               err_msg=msg)  # fmt: skip


@pytest.mark.parametrize("seed", SEEDS)
def test_a_turned_body_and_a_spiky_edge_widen_the_intervals(seed):
    t, x = _sine(seed)
    sd = np.full_like(t, 1.0)
    width = {yaw: np.diff(_intervals(t, x, sd, "knee_flexion_L", yaw_deg=yaw)["max_deg"])[0]
             for yaw in (0.0, 30.0, 60.0)}  # fmt: skip
    assert width[0.0] < width[30.0] < width[60.0], f"seed {seed}: {width}"
    # A still angle whose top 3 % of the frames jump 20° (a filter excursion) has a long upper tail: its peak
    # interval widens, its minimum's does not.
    rng = np.random.default_rng(seed)
    still = 10.0 + rng.normal(0.0, 0.5, t.size)
    spiky = still.copy()
    spiky[rng.choice(t.size, t.size * 3 // 100, replace=False)] += 20.0
    calm = _intervals(t, still, sd, "knee_flexion_L", yaw_deg=0.0)
    spike = _intervals(t, spiky, sd, "knee_flexion_L", yaw_deg=0.0)
    assert np.diff(spike["max_deg"])[0] > np.diff(calm["max_deg"])[0] + 20.0, f"seed {seed}: {spike} vs {calm}"
    np.testing.assert_allclose(np.diff(spike["min_deg"]), np.diff(calm["min_deg"]), atol=1.0)


@pytest.mark.parametrize("seed", SEEDS)
def test_a_kinect1_session_gets_its_device_gain(seed):
    """b grows by intervals.DEVICE_GAIN for a Kinect 1 session (larger errors); other devices keep the Kinect 2
    fit."""
    t, x = _sine(seed)
    sd = np.full_like(t, 1.0)
    e = intervals.edges(t, x, sd)
    assert e is not None
    b2 = intervals.systematic("knee_flexion_L", e, 30.0, "kinect2")
    b1 = intervals.systematic("knee_flexion_L", e, 30.0, "kinect1")
    np.testing.assert_allclose(b1, np.multiply(b2, intervals.DEVICE_GAIN["kinect1"]))
    assert intervals.systematic("knee_flexion_L", e, 30.0, "azure_kinect") == b2
    wide = _intervals(t, x, sd, "knee_flexion_L", yaw_deg=30.0, device="kinect1")["max_deg"]
    narrow = _intervals(t, x, sd, "knee_flexion_L", yaw_deg=30.0)["max_deg"]
    assert np.diff(wide)[0] > np.diff(narrow)[0], f"seed {seed}: {wide} vs {narrow}"


def _rotated(positions: np.ndarray, yaw_deg: float) -> np.ndarray:
    c, s = np.cos(np.radians(yaw_deg)), np.sin(np.radians(yaw_deg))
    R = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    return positions @ R.T


@pytest.mark.parametrize("yaw", (0.0, 20.0, 45.0, 70.0, 90.0))
def test_camera_yaw_reads_a_turned_skeleton(yaw):
    _, truth, _ = simulate("squat", 2, seed=1)  # the true body faces the camera; its shoulders sway about 1°
    front = intervals.camera_yaw(truth.positions)
    assert front is not None and front < 2.0
    for turn in (yaw, -yaw):
        turned = intervals.camera_yaw(_rotated(truth.positions, turn))
        assert turned is not None, turn
        np.testing.assert_allclose(turned, yaw, atol=front + 0.5)


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("view", (0, 30, 60))
def test_camera_yaw_reads_the_view_of_a_simulated_kinect_session(seed, view):
    measured, _, _ = simulate("shoulder_abduction", 3, view_deg=view, seed=seed)
    smoothed = series.smooth_positions(measured.t, process(measured).filtered.positions)
    yaw = intervals.camera_yaw(smoothed)
    assert yaw is not None and abs(yaw - view) < 8.0, f"view {view}, seed {seed}"


def test_camera_yaw_without_shoulders_and_bad_shapes():
    _, truth, _ = simulate("squat", 2, seed=1)
    p = truth.positions.copy()
    p[:, 4] = np.nan  # SHO_L
    assert intervals.camera_yaw(p) is None
    t = truth.t
    angles = {"knee_flexion_L": 20 + 10 * np.sin(t)}
    sd = {"knee_flexion_L": np.ones_like(t)}
    side_on = intervals.angle_intervals(t, angles["knee_flexion_L"], sd["knee_flexion_L"], "knee_flexion_L", yaw_deg=90)
    shown = intervals.rom_intervals(t, angles, sd, p)
    assert shown.intervals == {"knee_flexion_L": side_on} and shown.withheld == {}  # unknown yaw: side on, widest
    with pytest.raises(ValueError, match="positions"):
        intervals.camera_yaw(p[:, :10])


def test_no_interval_for_shoulder_rotation_or_a_spinning_angle():
    t, x = _sine(1)
    sd = np.ones_like(t)
    assert intervals.angle_intervals(t, x, sd, "shoulder_rotation_L", yaw_deg=0.0) is None
    assert intervals.angle_intervals(t, np.linspace(0, 720, t.size), sd, "elbow_flexion_L", yaw_deg=0.0) is None
    assert intervals.angle_intervals(t, np.full_like(t, np.nan), sd, "elbow_flexion_L", yaw_deg=0.0) is None


def test_a_range_never_goes_below_zero():
    t = np.arange(300) / 30.0
    iv = _intervals(t, np.full_like(t, 10.0), np.full_like(t, 5.0), "elbow_flexion_L", yaw_deg=0.0)
    assert iv["range_deg"][0] == 0.0


def test_shapes_are_checked():
    t, x = _sine(1)
    with pytest.raises(ValueError, match="shape"):
        intervals.angle_intervals(t, x[:-1], np.ones_like(t), "elbow_flexion_L", yaw_deg=0.0)


def test_covers_compares_the_ends_of_a_range_modulo_a_turn():
    assert intervals.covers([170.0, 190.0], -175.0, "max_deg")
    assert not intervals.covers([170.0, 190.0], -175.0, "range_deg")
    assert intervals.covers([0.0, 10.0], 10.0, "range_deg")


@pytest.mark.parametrize("seed", SEEDS)
def test_the_count_interval_holds_the_true_count_of_a_clean_session(seed):
    measured, _, _ = simulate("elbow_flexion", 6, seed=seed)
    result = process(measured)
    names = EXERCISES["elbow_flexion"].defining_angles
    smoothed = series.smooth_positions(measured.t, result.filtered.positions)
    angles = counting_angles(smoothed, names, joint_angles(smoothed))
    assert result.angle_sd is not None
    ci = intervals.count_interval(measured.t, angles, result.angle_sd, names)
    assert ci.low <= 6 <= ci.high, f"seed {seed}: {ci}"
    assert ci.high - ci.low <= 2, f"seed {seed}: {ci}"
    assert ci.to_dict()["ambiguous"] == (ci.low != ci.high)


@pytest.mark.parametrize("seed", SEEDS)
def test_intervals_stay_in_the_domain_and_consistent(seed):
    """A knee that straightens fully and bends to 175°, with SDs of 15°: no end leaves 0-180°, the range stays
    below what its ends allow."""
    t = np.arange(600) / 30.0
    rng = np.random.default_rng(seed)
    x = np.clip(87.5 + 90.0 * np.sin(2 * np.pi * t / 4.0 + rng.uniform(0, 6)), 0.0, 175.0)
    iv = _intervals(t, x, np.full_like(t, 15.0), "knee_flexion_L", yaw_deg=30.0)
    (a, b), (c, d), (e, f) = iv["min_deg"], iv["max_deg"], iv["range_deg"]
    assert 0.0 <= a <= b <= d <= 180.0 and a <= c <= d, f"seed {seed}: {iv}"
    assert 0.0 <= e <= f <= d - a, f"seed {seed}: {iv}"


def test_withheld_intervals_say_why():
    t, x = _sine(1)
    sd = np.ones_like(t)
    name = "knee_flexion_L"
    iv = intervals.angle_intervals(t, x, sd, name, yaw_deg=0.0)
    assert intervals.withheld_reason(name, x, iv) is None
    wide = intervals.angle_intervals(t, x, np.full_like(t, 30.0), name, yaw_deg=0.0)
    too_wide = intervals.withheld_reason(name, x, wide)
    assert too_wide is not None and too_wide.id == "too_uncertain" and float(too_wide.params["width"]) > 60, too_wide
    assert intervals.withheld_reason(name, x, iv, tracked_fraction=0.5) == Reason(
        id="joints_untracked", params={"tracked": 0.5})  # fmt: skip
    gappy = np.where(np.arange(t.size) % 3 == 0, x, np.nan)
    defined = intervals.withheld_reason(name, gappy, iv)
    assert defined is not None and defined.id == "out_of_plane", defined
    assert defined.params["defined"] == pytest.approx(1 / 3, abs=0.01), defined
    assert intervals.withheld_reason("shoulder_rotation_L", x, None) == Reason(id="rotation_undefined")
    shown = intervals.rom_intervals(t, {name: x}, {name: np.full_like(t, 30.0)}, np.full((t.size, 20, 3), np.nan))
    assert shown.intervals == {name: None} and shown.withheld[name].id == "too_uncertain"


@pytest.mark.parametrize("seed", SEEDS)
def test_a_defining_angle_is_not_widened_for_its_own_motion(seed):
    """A squat-like knee (standing still 70 % of the time, five dips to 100°): P99 − P90 of it is its motion, not an
    error. As the exercise's defining angle its peak interval takes the short tail (P99 − P97.5) and is narrower;
    rom_intervals passes `defining` through."""
    t = np.arange(900) / 30.0
    rng = np.random.default_rng(seed)
    phase = np.clip((t % 6.0) - 4.2, 0.0, None) / 1.8  # 1.8 s dip every 6 s
    x = 5.0 + 95.0 * np.sin(np.pi * phase) ** 2 + rng.normal(0.0, 0.5, t.size)
    sd = np.full_like(t, 4.0)
    other = intervals.angle_intervals(t, x, sd, "knee_flexion_L", yaw_deg=0.0)
    moving = intervals.angle_intervals(t, x, sd, "knee_flexion_L", yaw_deg=0.0, defining=True)
    assert moving is not None and other is not None
    assert np.diff(moving["max_deg"])[0] < 0.5 * np.diff(other["max_deg"])[0], f"seed {seed}: {moving} vs {other}"
    assert np.diff(moving["max_deg"])[0] <= intervals.MAX_WIDTH_DEG
    p = np.zeros((t.size, 20, 3))
    p[:, 4, 0], p[:, 8, 0] = -0.2, 0.2  # the shoulders face the camera
    shown = intervals.rom_intervals(t, {"knee_flexion_L": x}, {"knee_flexion_L": sd}, p, defining=("knee_flexion_L",))
    assert shown.intervals["knee_flexion_L"] == moving


def test_an_angle_whose_filtered_range_leaves_the_raw_envelope_has_its_intervals_withheld():
    raw = np.concatenate([np.linspace(20.0, 120.0, 200), [np.nan]])
    assert intervals.beyond_raw({"min_deg": 25.0, "max_deg": 125.0}, raw) == 0.0  # within 10° of raw's envelope
    off = intervals.beyond_raw({"min_deg": 25.0, "max_deg": 140.0}, raw)
    assert off == pytest.approx(140.0 - (119.5 + intervals.RAW_MARGIN_DEG)), off  # raw's 99.5th percentile: 119.5
    assert intervals.beyond_raw({"min_deg": None, "max_deg": None}, raw) == 0.0
    t, x = _sine(1)
    sd = np.ones_like(t)
    p = np.zeros((t.size, 20, 3))
    p[:, 4, 0], p[:, 8, 0] = -0.2, 0.2  # the shoulders face the camera
    name = "knee_flexion_L"
    shown = intervals.rom_intervals(t, {name: x}, {name: sd}, p, beyond={name: 0.0})
    assert shown.intervals[name] is not None and name not in shown.withheld
    held = intervals.rom_intervals(t, {name: x}, {name: sd}, p, beyond={name: 12.3})
    assert held.intervals[name] is None
    assert held.withheld[name] == Reason(id="beyond_raw", params={"by": 12.3})


def test_a_range_just_beyond_the_raw_data_never_reads_zero_degrees() -> None:
    assert intervals.beyond_raw_reason(0.0686) == Reason(id="beyond_raw", params={"by": 0.1})
    assert intervals.beyond_raw_reason(12.3) == Reason(id="beyond_raw", params={"by": 12.3})  # not 12.4 (12.3 × 10)
    text = reasons.written(intervals.beyond_raw_reason(0.0686), translator("en"))
    assert text == "the filtered curve reaches 0.1° beyond what the camera measured", text
