"""The segment-length noise of a recording (noise_level.py) and the exact-input settings it selects."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from kinect_agent.formats import keraal, ui_prmd
from kinect_agent.processing import noise_level
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.processing.pipeline import process
from kinect_agent.recording import Metadata, Recording
from kinect_agent.skeleton import NOT_TRACKED

from ._data import smooth_motion, utkinect


@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("sd_m", [0.005, 0.02])
def test_white_noise_is_estimated(seed: int, sd_m: float) -> None:
    """Independent noise of SD σ per axis on a moving rigid body reads σ within 15 %."""
    rng = np.random.default_rng(seed)
    t, truth, _ = smooth_motion(300, rng)
    rec = Recording.from_positions(t, truth + rng.normal(0.0, sd_m, truth.shape), Metadata(rate_hz=30.0))
    noise = noise_level.segment_noise_m(rec)
    assert noise is not None
    np.testing.assert_allclose(noise, sd_m, rtol=0.15, err_msg=f"seed {seed}, SD {sd_m} m")


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_exact_motion_is_rigid(seed: int) -> None:
    """The exact positions of a moving chain read < 1 µm, and are taken as exact under the default settings."""
    t, truth, _ = smooth_motion(120, np.random.default_rng(seed))
    noise = noise_level.segment_noise_m(Recording.from_positions(t, truth, Metadata(rate_hz=30.0)))
    assert noise is not None and noise < 1e-6, f"seed {seed}: {noise}"
    assert noise_level.is_rigid(noise, PipelineConfig())
    assert not noise_level.is_rigid(noise, PipelineConfig(rigid_input_sd_m=None))


def test_too_few_segments_give_no_estimate() -> None:
    """With fewer than MIN_SEGMENTS segments tracked in MIN_FRAMES frames there is no estimate (and no exact input)."""
    t, truth, _ = smooth_motion(60, np.random.default_rng(1))
    rec = Recording.from_positions(t, truth, Metadata(rate_hz=30.0))
    state = np.full_like(rec.state, NOT_TRACKED)
    state[:, :4] = rec.state[:, :4]  # ROOT, SPINE, NECK, HEAD: no segment of the paper's 14
    noise = noise_level.segment_noise_m(rec.replace(step="trunk only", positions=rec.positions, state=state))
    assert noise is None
    assert not noise_level.is_rigid(noise, PipelineConfig())


def test_real_kinect_recordings_are_not_rigid(data_dir: Path) -> None:
    """Real Kinect recordings read ≥ 2 × rigid_input_sd_m, so the exact-input settings never touch them: the
    lowest of all 119 shared recordings (UI-PRMD s01 m09, deep squats, 1.13 mm; bench/README.md, "Fed the truth,
    return the truth"), the KERAAL pairs and a UTKinect clip."""
    sd = PipelineConfig().rigid_input_sd_m
    assert sd is not None, "the default configuration has a rigid input sd"
    limit = 2 * sd
    kinect = data_dir / "ui-prmd" / "Segmented Movements" / "Kinect"
    recordings = {"ui-prmd s01 m09": ui_prmd.read_episodes(kinect, movement="m09", subject="s01")}
    for path in sorted((data_dir / "keraal" / "kinect_vicon_pairs").glob("G3-Kinect-*.txt")):
        recordings[path.name] = keraal.read(path)
    recordings["utkinect s01 e01"] = utkinect(data_dir)
    assert len(recordings) == 5, sorted(recordings)
    for name, rec in recordings.items():
        noise = noise_level.segment_noise_m(rec)
        assert noise is not None and noise >= limit, f"{name}: {noise} m"


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_filtered_recording_comes_back(seed: int) -> None:
    """A filtered recording (rigid by construction) fed again comes back within 5 mm on average, and is taken as
    exact; the first pass over the noisy input is not."""
    rng = np.random.default_rng(seed)
    t, truth, _ = smooth_motion(90, rng)
    noisy = Recording.from_positions(t, truth + rng.normal(0.0, 0.015, truth.shape), Metadata(rate_hz=30.0))
    first = process(noisy)
    again = process(first.filtered)
    error_mm = 1e3 * float(np.mean(np.linalg.norm(again.filtered.positions - first.filtered.positions, axis=-1)))
    assert not first.quality["rigid_input"] and again.quality["rigid_input"], (first.quality, again.quality)
    assert error_mm <= 5.0, f"seed {seed}: the filtered recording came back {error_mm:.1f} mm off"
