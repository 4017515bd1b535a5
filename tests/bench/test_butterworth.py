"""Zero-lag Butterworth baseline: passes slow motion, removes fast jitter, fills gaps, refuses bad input."""

import numpy as np
import pytest

from bench.baselines.butterworth import butterworth, winter_correction

RATE = 30.0
T_S = np.arange(600) / RATE


def _gain(freq_hz: float) -> float:
    x = np.sin(2 * np.pi * freq_hz * T_S)
    y = butterworth(T_S, x[:, None])[:, 0]
    mid = slice(150, 450)  # away from the ends
    return float(np.std(y[mid]) / np.std(x[mid]))


def test_passes_1hz() -> None:
    np.testing.assert_allclose(_gain(1.0), 1.0, atol=0.01, err_msg="1 Hz should pass unchanged")


def test_kills_12hz() -> None:
    assert _gain(12.0) < 0.02, f"12 Hz should be removed, gain {_gain(12.0):.4f}"


def test_minus_3db_at_cutoff_with_winter_correction() -> None:
    np.testing.assert_allclose(_gain(6.0), 1 / np.sqrt(2), atol=0.03, err_msg="zero-lag filter -3 dB at 6 Hz")
    np.testing.assert_allclose(winter_correction(2), 0.802, atol=5e-4)


def test_zero_lag() -> None:
    x = np.sin(2 * np.pi * 1.0 * T_S)
    y = butterworth(T_S, x[:, None])[:, 0]
    lag = np.argmax(np.correlate(y[100:500], x[90:510], mode="valid")) - 10
    assert lag == 0, f"lag {lag} frames"


def test_gaps_are_interpolated() -> None:
    x = np.stack([np.linspace(0, 1, 600)] * 3, axis=1)[:, None, :]
    z = x.copy()
    z[100:110] = np.nan
    y = butterworth(T_S, z)
    assert np.all(np.isfinite(y))
    np.testing.assert_allclose(y[100:110], x[100:110], atol=1e-6, err_msg="a line through a gap stays a line")


def test_shape_mismatch_raises() -> None:
    with pytest.raises(ValueError, match="positions must have shape"):
        butterworth(T_S, np.zeros((10, 3)))
