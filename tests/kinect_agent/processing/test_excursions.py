"""Sustained excursions: a joint that jumps away faster than a body moves, stays, and jumps back."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from numpy.lib.stride_tricks import sliding_window_view

from kinect_agent import formats, skeleton
from kinect_agent.cli import main
from kinect_agent.evaluation.pairs import well_estimated
from kinect_agent.formats import ui_prmd
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.processing.excursions import (
    LiveExcursions,
    excursion_probabilities,
    find_excursions,
    window_nanmedian,
)
from kinect_agent.processing.outliers import outlier_probabilities
from kinect_agent.processing.pipeline import process
from kinect_agent.recording import Recording

KINECT = Path("ui-prmd") / "Segmented Movements" / "Kinect"
WRI_R, HAN_R = skeleton.INDEX["WRI_R"], skeleton.INDEX["HAN_R"]


def _with_plateau(rec: Recording, start: int, frames: int = 36, off=(0.25, 0.45, -0.1)) -> tuple[Recording, slice]:
    """Returns (copy of rec whose WRI_R and HAN_R are held `off` (m) away from frame `start` for `frames` frames,
    jumping there and back in one frame as real Kinect failures do, span)."""
    span = slice(start, start + frames)
    positions = rec.positions.copy()
    positions[span, [WRI_R, HAN_R]] = positions[start - 1, [WRI_R, HAN_R]] + np.asarray(off)
    return rec.replace(step="test: sustained wrist loss", positions=positions), span


def _uiprmd(data_dir: Path, movement: str, subject: str) -> Recording:
    return ui_prmd.read_episodes(data_dir / KINECT, movement=movement, subject=subject)


@pytest.mark.shared_data
def test_plateau_injected_into_real_recording_is_found_and_nothing_else(data_dir: Path) -> None:
    rec, span = _with_plateau(_uiprmd(data_dir, "m07", "s01"), start=300)  # shoulder abduction: arms move fast
    config = PipelineConfig()
    flags = excursion_probabilities(rec, config) > config.outlier_threshold
    expected = np.zeros_like(flags)
    expected[span, [WRI_R, HAN_R]] = True
    np.testing.assert_array_equal(flags, expected, err_msg="exactly the held frames of the wrist and hand")
    temporal = outlier_probabilities(rec, config)[span, WRI_R] > config.outlier_threshold
    assert temporal.mean() < 0.5, "the temporal residual alone would keep most of the plateau (why this exists)"


@pytest.mark.shared_data
@pytest.mark.parametrize("movement", ["m07", "m09", "m10"])
def test_real_arm_exercises_are_not_flagged(data_dir: Path, movement: str) -> None:
    """UI-PRMD shoulder abduction, rotation and scaption: fast arms, clean tracking; nothing is an excursion."""
    for subject in ("s01", "s03", "s05"):
        assert not excursion_probabilities(_uiprmd(data_dir, movement, subject)).any(), (movement, subject)


@pytest.mark.shared_data
@pytest.mark.parametrize("subject", ["s02", "s04"])
def test_a_raised_knee_that_keeps_its_bones_is_not_an_excursion(data_dir: Path, subject: str) -> None:
    """UI-PRMD hurdle step: the knee is raised fast, held and lowered, like a lost joint's jump, sit and jump back,
    but thigh and shank keep their lengths (26 % of the right knee's frames were flagged, and the filtered hip
    angle then dipped mid-step: 15 repetitions counted for 10)."""
    flags = excursion_probabilities(_uiprmd(data_dir, "m02", subject))
    for joint in ("KNE_R", "ANK_R", "FOO_R", "KNE_L", "ANK_L", "FOO_L"):
        assert flags[:, skeleton.INDEX[joint]].mean() < 0.01, (subject, joint)


@pytest.mark.shared_data
def test_real_leg_raise_travelling_away_is_not_an_excursion(data_dir: Path) -> None:
    """UI-PRMD m06 s01: the raised leg glitches at the top of each raise; the standing phase between two glitches
    looks like jump away, sit, jump back, but the leg travelled there (calm steps), so it is kept (before the travel
    rule: 4.2 % of all joint-frames flagged)."""
    rec = _uiprmd(data_dir, "m06", "s01")
    assert excursion_probabilities(rec).mean() < 0.01


@pytest.mark.shared_data
def test_flags_on_real_pair_sit_far_from_vicon(data_dir: Path) -> None:
    from bench import real_pairs as rp

    kinect_path = next(p for p in rp.pair_paths() if "-ELK-" in p.name)
    kinect, vicon = rp.read_pair(kinect_path)
    good = well_estimated(vicon.meta.extra.get("fallback_joints", []))
    truth = rp.registered_truth(kinect, vicon, rp.align(kinect, vicon, good))
    offset = np.linalg.norm(kinect.positions - truth, axis=-1)[:, good]  # (T, G) m
    flags = (excursion_probabilities(kinect) > 0.95)[:, good]
    ok = np.isfinite(offset)
    assert (flags & ok).sum() >= 30, "the ELK right-wrist plateau (1.4 s, 0.9 m off) was not found"
    assert np.median(offset[flags & ok]) > 0.3 > 0.05 > np.median(offset[~flags & ok])


def test_continuous_fast_motion_and_one_way_jumps_are_not_excursions() -> None:
    t = np.arange(90) / 30.0
    swing = np.stack([0.6 * np.sin(2 * np.pi * t), np.zeros_like(t), np.full_like(t, 2.5)], axis=-1)  # 3.8 m/s peak
    assert find_excursions(t, swing, 4.0) == []
    step = np.where((t < 1.0)[:, None], [0.0, 1.0, 2.5], [0.4, 1.0, 2.5])  # jumps away, never back
    assert find_excursions(t, step, 2.0) == []
    brief = np.tile([0.0, 1.0, 2.5], (len(t), 1))
    brief[30:35, 0] += 0.4  # 0.17 s away: shorter than min_len_s, left to the temporal residual
    assert find_excursions(t, brief, 2.0) == []


@pytest.mark.shared_data
def test_pipeline_option_fills_the_plateau_from_the_model(data_dir: Path) -> None:
    original = _uiprmd(data_dir, "m07", "s01")
    rec, span = _with_plateau(original, start=300)
    err = {}
    for on in (False, True):
        out = process(rec, config=PipelineConfig(outlier_excursions=on)).filtered.positions
        err[on] = float(np.median(np.linalg.norm(out[span, WRI_R] - original.positions[span, WRI_R], axis=-1)))
    assert err[False] > 0.2 and err[True] < 0.1, f"median distance to the recorded wrist, m: {err}"


def test_filter_command_removes_excursions_unless_told_not_to(tmp_path: Path, rng: np.random.Generator) -> None:
    from ._data import smooth_motion

    t, truth, _ = smooth_motion(150, rng)
    still = np.broadcast_to(truth[0], truth.shape) + rng.normal(0.0, 0.005, truth.shape)  # a patient standing still
    rec, span = _with_plateau(Recording.from_positions(t, still), start=60)
    src = tmp_path / "in.csv"
    formats.write(rec, src)
    for flag in ([], ["--no-excursions"]):
        out = tmp_path / f"out{len(flag)}.csv"
        assert main(["filter", str(src), "-o", str(out), "--no-progress", *flag]) == 0
        wrist = formats.read(out).positions[span, WRI_R]
        off = float(np.median(np.linalg.norm(wrist - still[span, WRI_R], axis=-1)))
        assert (off < 0.05) if not flag else (off > 0.2), f"{flag}: wrist {off:.3f} m off"


def _held(rec: Recording, **kw) -> np.ndarray:
    live = LiveExcursions(**kw)
    present = np.all(np.isfinite(rec.positions), axis=-1)
    return np.array([live.step(float(t), p, ok) for t, p, ok in zip(rec.t, rec.positions, present, strict=True)])


@pytest.mark.shared_data
def test_live_filter_holds_the_injected_plateau_out(data_dir: Path) -> None:
    original = _uiprmd(data_dir, "m07", "s01")
    rec, span = _with_plateau(original, start=300)
    held = _held(rec)
    assert held[span, WRI_R].mean() > 0.9 and held[span, HAN_R].mean() > 0.9
    assert held.sum() <= held[span].sum() + 2, "held only around the plateau"
    err = {}
    for on in (False, True):
        out = process(rec, online=True, config=PipelineConfig(online_excursions=on)).filtered.positions
        err[on] = float(np.median(np.linalg.norm(out[span, WRI_R] - original.positions[span, WRI_R], axis=-1)))
    # causal: while held, the wrist follows the random walk of the arm's angles, not the moving arm (0.15 m here)
    assert err[False] > 0.5 and err[True] < 0.2, f"median distance to the recorded wrist, m: {err}"


@pytest.mark.shared_data
@pytest.mark.parametrize("movement", ["m07", "m09", "m10"])
def test_live_filter_holds_nothing_in_clean_real_arm_exercises(data_dir: Path, movement: str) -> None:
    for subject in ("s01", "s03", "s05"):
        assert not _held(_uiprmd(data_dir, movement, subject)).any(), (movement, subject)


def test_live_hold_ends_when_the_joint_never_comes_back() -> None:
    t = np.arange(180) / 30.0
    positions = np.tile(np.zeros(3), (180, skeleton.J, 1)) + np.arange(skeleton.J)[None, :, None] * 0.1
    positions[60:, WRI_R] += [0.5, 0.0, 0.0]  # jumps away at 2 s and stays there
    held = _held(Recording.from_positions(t, positions), max_len_s=1.0)[:, WRI_R]
    assert held[60:90].all() and not held[92:].any(), "held for max_len_s (1 s), then observed again"
    swing = np.stack([0.6 * np.sin(2 * np.pi * t), np.zeros_like(t), np.full_like(t, 2.5)], axis=-1)
    positions[:, WRI_R] = swing  # continuous, up to 3.8 m/s
    assert not _held(Recording.from_positions(t, positions))[:, WRI_R].any()


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_window_nanmedian_equals_numpys_nanmedian_of_the_windows(seed: int) -> None:
    """The jump context's median (compiled when numba is there) is numpy's, with gaps, ties, inf and empty windows."""
    rng = np.random.default_rng(seed)
    for trial in range(60):
        n = int(rng.integers(11, 300))
        x = rng.exponential(size=n)
        x[rng.random(n) < rng.uniform(0.0, 0.95)] = np.nan
        if trial % 3 == 0:
            x = np.round(x, 1)  # ties
        if trial % 4 == 0:
            x[rng.random(n) < 0.05] = np.inf
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            ref = np.nanmedian(sliding_window_view(x, 11), axis=1)
        np.testing.assert_array_equal(window_nanmedian(x, 11), ref, err_msg=f"seed {seed}, trial {trial}")
