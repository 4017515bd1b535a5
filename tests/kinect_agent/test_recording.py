"""Recording validates its arrays and keeps metadata through copies and concatenation."""

from __future__ import annotations

import numpy as np
import pytest

from kinect_agent import skeleton
from kinect_agent.recording import Metadata, Recording


def _positions(rng: np.random.Generator, frames: int) -> np.ndarray:
    return rng.normal(size=(frames, skeleton.J, 3))


def test_shape_errors_name_expected_and_actual(rng: np.random.Generator) -> None:
    with pytest.raises(ValueError, match=r"positions must have shape \(5, 20, 3\), got \(5, 19, 3\)"):
        Recording.from_positions(np.arange(5.0), rng.normal(size=(5, 19, 3)))


def test_time_must_increase(rng: np.random.Generator) -> None:
    with pytest.raises(ValueError, match="frame 2 has t=1.0 after t=1.0"):
        Recording.from_positions(np.array([0.0, 1.0, 1.0]), _positions(rng, 3))


def test_tracked_joint_needs_a_finite_position(rng: np.random.Generator) -> None:
    positions = _positions(rng, 2)
    positions[1, 3, 0] = np.inf
    state = np.full((2, skeleton.J), skeleton.TRACKED)
    with pytest.raises(ValueError, match="frame 1, joint HEAD"):
        Recording(np.arange(2.0), positions, state)


def test_from_positions_marks_nan_untracked(rng: np.random.Generator) -> None:
    positions = _positions(rng, 3)
    positions[0, 4] = np.nan
    rec = Recording.from_positions(np.arange(3.0), positions)
    assert rec.state[0, 4] == skeleton.NOT_TRACKED and rec.state[1, 4] == skeleton.TRACKED
    assert rec.tracked().sum() == 3 * skeleton.J - 1


def test_replace_copies_and_records_history(rng: np.random.Generator) -> None:
    rec = Recording.from_positions(np.arange(3.0), _positions(rng, 3), Metadata(device="kinect2"))
    out = rec.replace(step="smoothed")
    out.positions[0, 0] = 99.0
    assert rec.positions[0, 0, 0] != 99.0
    assert out.meta.history == ["smoothed"] and rec.meta.history == []


def test_concatenate_restarts_each_clock_one_frame_later(rng: np.random.Generator) -> None:
    parts = [Recording.from_positions(np.arange(n) / 30.0 + 5.0, _positions(rng, n), Metadata(rate_hz=30.0))
             for n in (3, 4)]  # fmt: skip
    whole = Recording.concatenate(parts)
    assert whole.n_frames == 7
    np.testing.assert_allclose(whole.t, np.arange(7) / 30.0, atol=1e-12)
    assert whole.meta.extra["part_start_s"] == pytest.approx([0.0, 3 / 30.0])


def test_rate_falls_back_to_median_time_step(rng: np.random.Generator) -> None:
    rec = Recording.from_positions(np.array([0.0, 0.05, 0.1, 0.2]), _positions(rng, 4))
    assert rec.rate_hz == pytest.approx(20.0)
