"""Kinect SDK Holt smoothing: the documented steady-state lag on ramps, deviation bound, reset on gaps."""

import numpy as np
import pytest

from bench.baselines.holt import JITTER_RADIUS_M, PREDICTION, holt_kinect


def _ramp(v_m_per_frame: float, n: int = 300) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(n) / 30.0
    x = np.zeros((n, 1, 3))
    x[:, 0, 0] = v_m_per_frame * np.arange(n)
    return t, x


def test_slow_ramp_lags_by_jitter_steady_state() -> None:
    v = 0.1 / 30.0  # 0.1 m/s: every step is inside the jitter radius
    t, x = _ramp(v)
    y = holt_kinect(t, x)
    expected = -(np.sqrt(v * JITTER_RADIUS_M) - v) + PREDICTION * v  # output - raw in steady state
    np.testing.assert_allclose(y[-1, 0, 0] - x[-1, 0, 0], expected, atol=1e-6, err_msg="slow-ramp lag")


def test_fast_ramp_leads_by_prediction() -> None:
    v = 0.04  # 1.2 m/s: steps beyond the jitter radius pass the jitter stage
    t, x = _ramp(v)
    y = holt_kinect(t, x)
    np.testing.assert_allclose(y[-1, 0, 0] - x[-1, 0, 0], PREDICTION * v, atol=1e-6, err_msg="fast-ramp lead")


def test_output_stays_within_max_deviation() -> None:
    t, x = _ramp(0.0)
    x[100:, 0, 1] = 1.0  # a 1 m jump
    y = holt_kinect(t, x)
    dev = np.linalg.norm(y - x, axis=-1)
    assert dev.max() <= 0.05 + 1e-9, f"deviation {dev.max():.4f} m beyond the 5 cm radius"


def test_constant_is_kept_exactly() -> None:
    t, x = _ramp(0.0)
    x += 0.7
    np.testing.assert_allclose(holt_kinect(t, x), x, atol=1e-12)


def test_gap_resets_and_gives_nan() -> None:
    t, x = _ramp(0.04)
    x[50] = np.nan
    y = holt_kinect(t, x)
    assert np.all(np.isnan(y[50]))
    np.testing.assert_allclose(y[51], x[51], err_msg="first frame after a reset is the raw position")


def test_bad_state_shape_raises() -> None:
    t, x = _ramp(0.0, 10)
    with pytest.raises(ValueError, match="state must have shape"):
        holt_kinect(t, x, np.zeros((10, 2)))
