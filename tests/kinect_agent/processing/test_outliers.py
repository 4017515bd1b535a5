"""Mixture-model outlier removal: the EM fit, and outliers found in simulated and real recordings."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from kinect_agent import skeleton
from kinect_agent.processing.outliers import fit_mixture, outlier_probabilities, remove_outliers
from kinect_agent.recording import Metadata, Recording

from ._data import inject_outliers, smooth_motion, utkinect


def _recall_precision(flag: np.ndarray, mask: np.ndarray, ignore: np.ndarray | None = None) -> tuple[float, float]:
    ignore = np.zeros_like(mask) if ignore is None else ignore
    tp = np.sum(flag & mask)
    fp = np.sum(flag & ~mask & ~ignore)
    return tp / max(mask.sum(), 1), tp / max(tp + fp, 1)


def test_em_recovers_the_mixture_parameters(rng: np.random.Generator) -> None:
    n = 4000
    gauss = rng.normal([0.01, -0.02], [0.02, 0.05], size=(n, 2))  # two columns, scalars
    uniform = rng.uniform(-1.0, 1.0, size=(n, 2))
    pick = rng.random((n, 2)) < 0.8
    x = np.where(pick, gauss, uniform)
    fit = fit_mixture(x)
    np.testing.assert_allclose(fit.rho[0], [0.8, 0.8], atol=0.03, err_msg="rho")
    np.testing.assert_allclose(fit.mu[:, 0], [0.01, -0.02], atol=0.005, err_msg="mu")
    np.testing.assert_allclose(fit.sigma[:, 0], [0.02, 0.05], rtol=0.08, err_msg="sigma")
    np.testing.assert_allclose(fit.x1[:, 0], x.min(0), err_msg="uniform range is the data range")


def test_em_fits_separate_weights_per_tracking_state(rng: np.random.Generator) -> None:
    n = 6000
    cls = (rng.random((n, 1)) < 0.5).astype(int)  # class 1 (inferred) has more outliers
    p_out = np.where(cls == 1, 0.4, 0.05)
    x = np.where(rng.random((n, 1)) < p_out, rng.uniform(-1, 1, (n, 1)), rng.normal(0, 0.02, (n, 1)))
    fit = fit_mixture(x, cls, n_classes=2)
    np.testing.assert_allclose(fit.rho[:, 0], [0.95, 0.6], atol=0.03)


def test_em_ignores_nan_and_names_bad_shapes(rng: np.random.Generator) -> None:
    x = rng.normal(0, 0.01, (500, 3))
    x[::7] = np.nan
    fit = fit_mixture(x)
    assert np.all(np.isfinite(fit.mu)) and np.all(fit.n == np.isfinite(x).sum(0))
    with pytest.raises(ValueError, match=r"cls must have shape \(500, 3\)"):
        fit_mixture(x, np.zeros((500, 2), int))


def test_injected_outliers_are_found_in_simulated_motion(rng: np.random.Generator) -> None:
    t, truth, _ = smooth_motion(240, rng)
    noisy = truth + rng.normal(0, 0.015, truth.shape)
    rec = Recording.from_positions(t, noisy, Metadata(rate_hz=30.0, device="simulator"))
    bad, mask = inject_outliers(rec, rng)
    recall, precision = _recall_precision(outlier_probabilities(bad) > 0.5, mask)
    assert recall >= 0.95 and precision >= 0.9, f"recall {recall:.3f}, precision {precision:.3f}"


@pytest.mark.parametrize("name", ["joints_s01_e01.txt", "joints_s03_e02.txt", "joints_s05_e01.txt"])
def test_injected_outliers_are_found_in_real_kinect_recordings(data_dir: Path, name: str) -> None:
    """UTKinect (Kinect v1, ~8 Hz skeletons, walking and sitting): a hard case. Samples the method already flags
    in the untouched recording are real glitches, not false positives of the injection."""
    rec = utkinect(data_dir, name, frames=240)
    own = outlier_probabilities(rec) > 0.5
    bad, mask = inject_outliers(rec, np.random.default_rng(7))
    recall, precision = _recall_precision(outlier_probabilities(bad) > 0.5, mask, own)
    assert recall >= 0.95 and precision >= 0.85, f"{name}: recall {recall:.3f}, precision {precision:.3f}"


def test_remove_outliers_makes_them_missing_not_zero(rng: np.random.Generator) -> None:
    t, truth, _ = smooth_motion(120, rng)
    rec = Recording.from_positions(t, truth + rng.normal(0, 0.01, truth.shape))
    bad, mask = inject_outliers(rec, rng)
    clean, prob = remove_outliers(bad)
    removed = clean.state == skeleton.NOT_TRACKED
    assert removed[mask].mean() >= 0.95
    assert np.all(np.isnan(clean.positions[removed])), "removed samples must be NaN"
    assert not np.any(clean.positions == 0.0)
    assert prob.shape == (120, skeleton.J) and np.all((prob >= 0) & (prob <= 1))
    assert "outliers mixture-model" in clean.meta.history[-1]
    assert np.all(bad.state[mask] == skeleton.TRACKED), "the input must not change"


def test_untracked_joints_are_missing_with_probability_one(rng: np.random.Generator) -> None:
    t, truth, _ = smooth_motion(60, rng)
    truth[10:15, 3] = np.nan
    prob = outlier_probabilities(Recording.from_positions(t, truth))
    assert np.all(prob[10:15, 3] == 1.0)
