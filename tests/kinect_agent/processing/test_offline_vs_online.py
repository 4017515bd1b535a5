"""The offline smoother against the causal passes it builds on, per joint (issue 24, point 2).

Short clips of every source with a truth (an HDM05 kick, CMU 13_29 arm circles, a UI-PRMD deep squat driven by its
Vicon episode, a simulated side step), measured by
white noise (20 mm per axis) and by the project's Kinect 2 model, each at two (view, seed) pairs. Per joint RMSE
against the truth, mm. bench/offline_vs_online.py measures the same over every motion, view and seed
(bench/README.md, "Offline smoother against its own online filter, per joint").
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from kinect_agent import skeleton
from kinect_agent.blas_threads import one_blas_thread
from kinect_agent.formats import amc, bvh, ui_prmd_vicon
from kinect_agent.processing.combined_outliers import remove_outliers_combined
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.processing.ik import inverse_kinematics
from kinect_agent.processing.pipeline import process, smooth
from kinect_agent.recording import Recording
from kinect_agent.sources.kinect_noise import add_kinect_noise
from kinect_agent.sources.mocap_truth import heading_deg, place_in_camera, resample
from kinect_agent.sources.simulator import simulate
from tests.conftest import DATA

RATE_HZ = 30.0
WHITE_M = 0.02
CASES = [(0, 1), (60, 2)]  # (view degrees, seed)
# A joint "loses" when its RMSE exceeds the other estimate's by more than this, mm. Measured on these clips (white
# noise): the RTS pass against its forward pass −0.7 to +0.2 mm at the worst joint of each clip; the offline pipeline
# against the online filter +4.3 to +19.5 mm (bench/README.md). 1 mm is room for rounding and seed noise, an order
# below the losses the property is about.
TOLERANCE_MM = 1.0


@dataclass
class Clip:
    """One measured clip: its name (source, noise, view, seed), the measurement and its truth (T, J, 3) m."""

    name: str
    measured: Recording
    truth: np.ndarray


def _mocap(data_dir: Path) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Returns {source: (t (T,) s, positions (T, J, 3) m, mocap frame)} at 30 Hz: one HDM05 kick (actor bd, one
    repetition), the first 3 s of CMU 13_29's arm circles (mocap6 labels) and UI-PRMD s01's first deep squat (Vicon
    joint positions, the truth bench/accuracy.py drives its UI-PRMD rows with)."""
    out = {}
    squat = data_dir / "ui-prmd" / "Segmented Movements" / "Vicon" / "Positions" / "m01_s01_e01_positions.txt.gz"
    if squat.is_file():
        out["ui-prmd deep squat"] = resample(ui_prmd_vicon.read(squat), RATE_HZ)
    kick = data_dir / "hdm05" / "kickLFront1Reps" / "HDM_bd_kickLFront1Reps_001_120.amc"
    if kick.is_file():
        out["hdm05 kick"] = resample(amc.read(kick), RATE_HZ)
    cmu = data_dir / "cmu-mocap" / "13_29.bvh"
    labels = cmu.with_name("13_29_segments_from_mocap6.csv")
    if cmu.is_file() and labels.is_file():
        row = next(r for r in labels.read_text(encoding="utf-8").splitlines() if r.startswith("ArmCircle,"))
        first = int(int(row.split(",")[3]) * RATE_HZ / 120.0)
        t, p = resample(bvh.read(cmu), RATE_HZ)
        window = slice(first, first + int(3 * RATE_HZ))
        out["cmu arm circles"] = (t[window] - t[window][0], p[window])
    return out


def _measure(t: np.ndarray, p: np.ndarray, view: int, seed: int, white: bool) -> tuple[Recording, np.ndarray]:
    """Returns (measured recording, truth positions (T, J, 3) m in the camera frame) of a mocap clip."""
    truth = Recording.from_positions(t, place_in_camera(p, view, heading_deg(p)))
    truth.meta.rate_hz = RATE_HZ
    rng = np.random.default_rng([seed, view, 24])
    if white:
        noisy = truth.positions + WHITE_M * rng.standard_normal(truth.positions.shape)
        return truth.replace(step="white noise", positions=noisy), truth.positions
    measured, _ = add_kinect_noise(truth, device="kinect2", view_deg=view, pose="standing", rng=rng)
    return measured, truth.positions


def _simulated(view: int, seed: int, white: bool) -> tuple[Recording, np.ndarray]:
    """Returns (measured, truth (T, J, 3) m) of one simulated side step (the Kinect 2 model, or white noise)."""
    measured, truth, _ = simulate("side_step", 1, view_deg=view, seed=seed)
    if white:
        noisy = truth.positions + WHITE_M * np.random.default_rng([seed, view, 24]).standard_normal(
            truth.positions.shape
        )
        measured = truth.replace(step="white noise", positions=noisy)
    return measured, truth.positions


@pytest.fixture(scope="module")
def clips() -> list[Clip]:
    """Every clip, built once for the module (the mocap sources only where ../shared/data holds them; CI has it)."""
    if not DATA.is_dir() and os.environ.get("CI"):
        pytest.fail(f"{DATA} is missing; CI must have ../shared beside the repository")
    mocap = _mocap(DATA) if DATA.is_dir() else {}
    expected = {"hdm05 kick", "cmu arm circles", "ui-prmd deep squat"}
    assert not DATA.is_dir() or set(mocap) == expected, f"mocap clips missing in {DATA}"
    out = []
    for white in (True, False):
        noise = "white 20 mm" if white else "Kinect 2 model"
        for view, seed in CASES:
            for source, (t, p) in mocap.items():
                out.append(Clip(f"{source}, {noise}, {view}° seed {seed}", *_measure(t, p, view, seed, white)))
            out.append(Clip(f"sim side step, {noise}, {view}° seed {seed}", *_simulated(view, seed, white)))
    return out


def _rmse_mm(est: np.ndarray, truth: np.ndarray) -> np.ndarray:
    return 1e3 * np.sqrt(np.mean(np.sum((est - truth) ** 2, axis=-1), axis=0))


def _losses(name: str, a: np.ndarray, b: np.ndarray) -> list[str]:
    return [f"{name}: {skeleton.JOINTS[j]} {a[j]:.1f} > {b[j]:.1f} mm" for j in np.flatnonzero(a > b + TOLERANCE_MM)]


def test_smoother_never_worse_than_its_forward_pass_under_white_noise(clips: list[Clip]) -> None:
    """The unscented RTS pass, per joint, is never worse than the forward pass 3 it smooths (same lengths, same noise
    model, shipped defaults) where the noise is what the filter assumes: independent per joint and frame. Measured on
    these clips: margins −0.7 to +0.2 mm. Under the Kinect model it is not a property of any smoother: the Kinect's
    error is slow and biased, and the RTS pass lost by up to 3.5 mm (ROOT, the 1.4-s kick at 0°) there. Over the whole
    benchmark (bench/offline_vs_online.py --forward) it also fails on fast mocap: 18 of 108 rows, up to +14.3 mm at the
    hands of HDM05 arm circles, where the shoulders' rotation vectors wrap past π (bench/README.md)."""
    config = PipelineConfig()
    lost = []
    with one_blas_thread():
        for clip in (c for c in clips if "white" in c.name):
            clean, _ = remove_outliers_combined(clip.measured, config)
            ik = inverse_kinematics(clean.positions)
            root, lengths, theta, info = smooth(clean, ik, config, forward=True)
            lengths_t = np.broadcast_to(lengths, (clean.n_frames, len(lengths)))
            smoothed = ik.model.positions(root, lengths_t, theta)
            f_root, f_theta = info["forward"]
            forward = ik.model.positions(f_root, lengths_t, f_theta)
            lost += _losses(clip.name, _rmse_mm(smoothed, clip.truth), _rmse_mm(forward, clip.truth))
    assert not lost, "; ".join(lost)


@pytest.mark.xfail(
    strict=True,
    raises=AssertionError,
    reason="issue 24 point 2 open: the shipped offline settings lose to the online filter at distal joints under "
    "white noise (the length passes stretch the bones) and at trunk and foot joints under the Kinect model; the "
    "measured fixes cost the real KERAAL pairs or, with the length-bias step, the UI-PRMD counts, and the Kinect "
    "model still loses at the trunk (bench/README.md, A segment-length bias step)",
)
def test_offline_never_worse_than_online(clips: list[Clip]) -> None:
    """process() offline, per joint, is never worse than process(online=True) on the same input, under white noise
    and the Kinect model. Fails today (strict: it must be turned into a plain test when it holds)."""
    lost = []
    for clip in clips:
        offline = process(clip.measured).filtered.positions
        online = process(clip.measured, online=True).filtered.positions
        lost += _losses(clip.name, _rmse_mm(offline, clip.truth), _rmse_mm(online, clip.truth))
    assert not lost, "; ".join(lost)
