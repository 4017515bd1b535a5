"""One Euro filter: reduces jitter on a constant, follows fast motion, restarts after gaps."""

import numpy as np
import pytest

from bench.baselines.one_euro import one_euro


def test_reduces_jitter_on_a_constant() -> None:
    rng = np.random.default_rng(0)
    t = np.arange(900) / 30.0
    z = 0.5 + 0.01 * rng.standard_normal((900, 3))
    y = one_euro(t, z)
    before, after = np.std(z[30:]), np.std(y[30:])
    assert after < 0.5 * before, f"jitter SD {after * 1e3:.2f} mm not below half of {before * 1e3:.2f} mm"
    np.testing.assert_allclose(np.mean(y[30:]), 0.5, atol=2e-3)


def test_higher_beta_lags_less_in_motion() -> None:
    t = np.arange(300) / 30.0
    x = np.sin(2 * np.pi * 1.0 * t)[:, None]
    err = [np.sqrt(np.mean((one_euro(t, x, beta=b)[60:] - x[60:]) ** 2)) for b in (0.0, 5.0)]
    assert err[1] < 0.5 * err[0], f"RMSE beta 0: {err[0]:.3f}, beta 5: {err[1]:.3f}"


def test_first_sample_and_restart_after_gap() -> None:
    t = np.arange(10) / 30.0
    x = np.arange(10.0)[:, None]
    x[4] = np.nan
    y = one_euro(t, x)
    assert y[0, 0] == 0.0 and np.isnan(y[4, 0]) and y[5, 0] == 5.0


def test_bad_parameters_raise() -> None:
    with pytest.raises(ValueError, match="min_cutoff"):
        one_euro(np.arange(3.0), np.zeros((3, 1)), min_cutoff=0.0)
