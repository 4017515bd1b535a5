"""The fused compiled UKF step (_ukf_numba) against the numpy reference (the filter's gated_update, numpy FK)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from kinect_agent import skeleton
from kinect_agent.body import kinematics as km
from kinect_agent.processing import _blas_numba, _ukf_numba
from kinect_agent.processing.chain_filter import ChainFilter, FrameData
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.processing.ik import inverse_kinematics
from kinect_agent.processing.pipeline import observations
from kinect_agent.recording import Metadata, Recording

from ._data import inject_outliers, smooth_motion

pytestmark = pytest.mark.skipif(not _ukf_numba.AVAILABLE, reason="numba not installed")


def _recording(rng: np.random.Generator, frames: int = 60) -> Recording:
    """Noisy smooth motion with missing joints, inferred joints and tracking-loss outliers (so the gate acts)."""
    t, truth, _ = smooth_motion(frames, rng)
    positions = truth + rng.normal(0.0, 0.015, truth.shape)
    positions[rng.random((frames, skeleton.J)) < 0.1] = np.nan
    rec = Recording.from_positions(t, positions, Metadata(rate_hz=30.0))
    state = rec.state.copy()
    state[(rng.random(state.shape) < 0.1) & (state == skeleton.TRACKED)] = skeleton.INFERRED
    rec = rec.replace(step="test: inferred joints", state=state)
    return inject_outliers(rec, rng, rate=0.02)[0]


def _filters(rec: Recording, fixed: bool, at_mean: bool = False) -> tuple[Any, ...]:
    """Returns (fast, reference) filters with the same chain and start; the reference uses numpy throughout."""
    fit = inverse_kinematics(rec.positions)
    lengths = fit.lengths if fixed else None
    config = PipelineConfig(innovation_at_mean=at_mean)
    x0 = np.concatenate([fit.root[0]] + ([] if fixed else [fit.lengths]) + [fit.theta[0]])
    fast = ChainFilter(fit.model, lengths, config, x0)
    plain_model = km.ChainModel(fit.model.rest, fit.model.R_ref, compiled=False)
    ref = ChainFilter(plain_model, lengths, config, x0)
    assert fast.compiled and not ref.compiled
    return fast, ref, config


@pytest.mark.parametrize("at_mean", [False, True], ids=["innovation at the sigma mean", "innovation at h(x̄)"])
@pytest.mark.parametrize("fixed", [True, False], ids=["lengths fixed (n=36)", "lengths in the state (n=55)"])
def test_fast_step_equals_the_reference_step(rng: np.random.Generator, fixed: bool, at_mean: bool) -> None:
    rec = _recording(rng)
    fast, ref, config = _filters(rec, fixed, at_mean)
    z, observed, R_diag = observations(rec, config)
    gated = 0
    for k in range(rec.n_frames):
        for kf in (fast, ref):
            kf.predict_random_walk(1.0)
        used_fast = fast.update_joints(z[k], observed[k], R_diag[k], config.gate_chi2)
        used_ref = ref.update_joints(z[k], observed[k], R_diag[k], config.gate_chi2)
        np.testing.assert_array_equal(used_fast, used_ref, err_msg=f"joints used at frame {k}")
        np.testing.assert_allclose(fast.x, ref.x, rtol=0, atol=1e-9, err_msg=f"state at frame {k}")
        np.testing.assert_allclose(fast.P, ref.P, rtol=0, atol=1e-9, err_msg=f"covariance at frame {k}")
        gated += int(observed[k].reshape(-1, 3).all(axis=1).sum() - used_ref.sum())
    assert gated > 0, "the test data should make the gate drop some joints"


def test_fast_step_refuses_a_covariance_that_is_not_positive_definite(rng: np.random.Generator) -> None:
    fast, _, config = _filters(_recording(rng, 10), fixed=True)
    fast.P[0, 0] = -1.0
    x, P = fast.x.copy(), fast.P.copy()
    z, observed, R_diag = observations(_recording(rng, 10), config)
    used = np.empty(skeleton.J, dtype=bool)
    status = _ukf_numba.chain_step(
        fast.x, fast.P, z[0], observed[0], R_diag[0], fast.kernel_weights, 30.0, fast.fixed_lengths, fast.n_len,
        fast.model.rest, fast.model.R_ref, km.STEP_TABLES, used,
    )  # fmt: skip
    assert status == _ukf_numba.P_NOT_POSITIVE
    np.testing.assert_array_equal(fast.x, x, err_msg="x changed although the step was refused")
    np.testing.assert_array_equal(fast.P, P, err_msg="P changed although the step was refused")


def test_sincos_is_libm_to_one_ulp() -> None:
    x = np.concatenate([np.linspace(-40.0, 40.0, 100_001), np.linspace(-1e-9, 1e-9, 101), [0.0, np.pi, -np.pi / 2]])
    got = np.array([_ukf_numba._sincos_c(v) for v in x[::50]])
    np.testing.assert_allclose(got[:, 0], np.sin(x[::50]), rtol=0, atol=2.3e-16)
    np.testing.assert_allclose(got[:, 1], np.cos(x[::50]), rtol=0, atol=2.3e-16)


def test_lapack_wrappers_match_numpy(rng: np.random.Generator) -> None:
    A = rng.normal(size=(12, 7))
    S = A.T @ A + np.eye(7)
    L = S.copy()
    assert _blas_numba.cholesky_lower(L, 7) == 0
    np.testing.assert_allclose(np.tril(L), np.linalg.cholesky(S), atol=1e-12)
    B = rng.normal(size=(7, 4))
    X = B.copy()
    _blas_numba.solve_lower(L, 7, X, 7, 4)
    np.testing.assert_allclose(X, np.linalg.solve(np.tril(L), B), atol=1e-12)
    C = np.zeros((7, 7))
    _blas_numba.gram_lower(A, 12, 7, 2.0, 0.0, C)
    np.testing.assert_allclose(np.tril(C), np.tril(2.0 * A.T @ A), atol=1e-12)
    G = np.zeros((12, 12))
    _blas_numba.gram_rows_lower(A.reshape(-1)[1:], 12, 6, 7, 0.5, G)  # A[:, 1:] · A[:, 1:]ᵀ
    np.testing.assert_allclose(np.tril(G), np.tril(0.5 * A[:, 1:] @ A[:, 1:].T), atol=1e-12)
    bad = -np.eye(3)
    assert _blas_numba.cholesky_lower(bad, 3) > 0


def _pass_by_methods(
    kf: ChainFilter, frames: FrameData, q_steps: np.ndarray, config: PipelineConfig, restart: tuple[np.ndarray, int]
) -> tuple[np.ndarray, np.ndarray, int]:
    """Runs a forward pass frame by frame through the filter's methods (the loop run_frames compiles); returns
    (xs (T, n), Ps (T, n, n), gated)."""
    T = len(frames.z)
    xs, Ps = np.empty((T, kf.dim_x)), np.empty((T, kf.dim_x, kf.dim_x))
    run = np.zeros(skeleton.J, dtype=np.int64)
    gated = 0
    for k in range(T):
        if k:
            kf.predict_random_walk(q_steps[k])
        if frames.any_observed[k]:
            lost = frames.present[k] & (run >= restart[1])
            if lost.any():
                kf.reacquire(np.flatnonzero(lost), restart[0][k])
                run[lost] = 0
            used = kf.update_joints(frames.z[k], frames.observed[k], frames.R_diag[k], config.gate_chi2)
            gated += int(frames.n_present[k]) - int(np.count_nonzero(used))
            run += frames.present[k] & ~used
            run[used] = 0
        xs[k], Ps[k] = kf.x, kf.P
    return xs, Ps, gated


@pytest.mark.parametrize("fixed", [True, False], ids=["lengths fixed (n=36)", "lengths in the state (n=55)"])
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_compiled_pass_equals_the_methods_frame_by_frame(seed: int, fixed: bool) -> None:
    rng = np.random.default_rng(seed)
    rec = _recording(rng, frames=150)
    fast, _, config = _filters(rec, fixed)
    ref, _, _ = _filters(rec, fixed)
    frames = FrameData.of(*observations(rec, config))
    q_steps = rng.uniform(0.5, 2.0, rec.n_frames)
    fit = inverse_kinematics(rec.positions)
    restart = (np.concatenate((fit.root, fit.theta), axis=1), 2)  # re-acquire after 2 gated frames: it happens
    xs_ref, Ps_ref, gated_ref = _pass_by_methods(ref, frames, q_steps, config, restart)
    xs, Ps = np.empty_like(xs_ref), np.empty_like(Ps_ref)
    run = np.zeros(skeleton.J, dtype=np.int64)
    order = np.arange(rec.n_frames)
    done, gated = 0, 0
    for begin in range(0, rec.n_frames, 40):  # in stretches, as the pipeline runs it
        done, g = fast.run_frames(frames, order, q_steps, (begin, min(begin + 40, rec.n_frames)), config.gate_chi2,
                                  restart, run, (xs, Ps))  # fmt: skip
        gated += g
    assert done == rec.n_frames, "no frame should need numpy's fallback here"
    assert gated == gated_ref > 0, "gated joint samples"
    np.testing.assert_array_equal(xs, xs_ref, err_msg="states")
    np.testing.assert_array_equal(Ps, Ps_ref, err_msg="covariances")
    np.testing.assert_array_equal(fast.x_prior, ref.x_prior, err_msg="x_prior of the last update")


def test_compiled_pass_stops_at_a_declined_update(rng: np.random.Generator) -> None:
    rec = _recording(rng, frames=20)
    fast, _, config = _filters(rec, fixed=True)
    frames = FrameData.of(*observations(rec, config))
    fast.P[0, 0] = -1.0  # not positive definite: chain_step declines the first update
    x = fast.x.copy()
    run = np.zeros(skeleton.J, dtype=np.int64)
    done, _ = fast.run_frames(frames, np.arange(20), np.ones(20), (0, 20), config.gate_chi2, None, run, None)
    assert done == 0, "the pass should stop at frame 0 for numpy's fallback"
    np.testing.assert_array_equal(fast.x, x, err_msg="x changed although the update was declined")
