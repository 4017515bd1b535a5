"""series.smooth_positions: the fast path (every column finite) equals the column-by-column definition."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter1d

from kinect_agent.analysis import series
from tests.kinect_agent.analysis._data import noisy


def _reference(t: np.ndarray, positions: np.ndarray) -> np.ndarray:
    """The first definition: gaps filled per column, then the Gaussian over the finite columns only."""
    flat = positions.reshape(positions.shape[0], -1).copy()
    for k in np.flatnonzero((~np.isfinite(flat)).any(axis=0)):
        flat[:, k] = series.fill_gaps(t, flat[:, k])
    sigma = series.SMOOTH_S / series.frame_interval(t)
    ok = np.isfinite(flat).all(axis=0)
    flat[:, ok] = gaussian_filter1d(flat[:, ok], sigma, axis=0, mode="nearest", truncate=series.TRUNCATE)
    return flat.reshape(positions.shape)


@pytest.mark.parametrize("which", ["measured", "truth"])
def test_smooth_positions_equals_reference(which: str) -> None:
    measured, truth = noisy("squat", 3, 2)
    rec = measured if which == "measured" else truth
    np.testing.assert_array_equal(series.smooth_positions(rec.t, rec.positions), _reference(rec.t, rec.positions))


def test_smooth_positions_keeps_never_tracked_joint_nan() -> None:
    _, truth = noisy("squat", 3, 2)
    positions = truth.positions.copy()
    positions[:, 7] = np.nan
    out = series.smooth_positions(truth.t, positions)
    assert np.all(np.isnan(out[:, 7]))
    np.testing.assert_array_equal(out, _reference(truth.t, positions))


def test_smooth_positions_does_not_change_its_input() -> None:
    _, truth = noisy("squat", 3, 2)
    before = truth.positions.copy()
    series.smooth_positions(truth.t, truth.positions)
    np.testing.assert_array_equal(truth.positions, before)
