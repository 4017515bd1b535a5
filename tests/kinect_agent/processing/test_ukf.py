"""The UKF core against a linear Kalman filter on a linear problem, and the smoother/combination helpers."""

from __future__ import annotations

import numpy as np
import pytest

from kinect_agent.processing import _rts_numba
from kinect_agent.processing.errors import NotPositiveDefinite, ProcessingError
from kinect_agent.processing.ukf import (
    MerweScaledSigmaPoints,
    UnscentedKalmanFilter,
    combine_information,
    unscented_rts,
)


def _linear_problem(rng: np.random.Generator, steps: int = 40):
    """A 2-D constant-velocity target seen through a random 3x4 observation matrix; some rows missing."""
    dt = 0.1
    F = np.eye(4)
    F[0, 2] = F[1, 3] = dt
    H = rng.normal(size=(3, 4))
    Q = np.diag([1e-4, 1e-4, 1e-2, 1e-2])
    R = np.diag([0.04, 0.09, 0.01])
    x, z_list = np.array([0.0, 0.0, 1.0, -0.5]), []
    for _ in range(steps):
        x = F @ x + rng.multivariate_normal(np.zeros(4), Q)
        z_list.append(H @ x + rng.multivariate_normal(np.zeros(3), R))
    zs = np.array(z_list)
    observed = rng.random(zs.shape) > 0.3
    observed[5] = False  # a frame with nothing observed
    return F, H, Q, R, zs, observed


def _kalman(F, H, Q, R, zs, observed, x0, P0):
    """The textbook linear Kalman filter with per-step subsets of observation rows (the reference)."""
    x, P, xs, Ps = x0.copy(), P0.copy(), [], []
    for z, obs in zip(zs, observed, strict=True):
        x, P = F @ x, F @ P @ F.T + Q
        if obs.any():
            Ho, Ro = H[obs], R[np.ix_(obs, obs)]
            S = Ho @ P @ Ho.T + Ro
            K = P @ Ho.T @ np.linalg.inv(S)
            x = x + K @ (z[obs] - Ho @ x)
            P = (np.eye(len(x)) - K @ Ho) @ P
        xs.append(x)
        Ps.append(P)
    return np.array(xs), np.array(Ps)


def test_ukf_equals_kalman_filter_on_a_linear_problem(rng: np.random.Generator) -> None:
    F, H, Q, R, zs, observed = _linear_problem(rng)
    x0, P0 = np.zeros(4), np.eye(4)
    ref_x, ref_P = _kalman(F, H, Q, R, zs, observed, x0, P0)
    ukf = UnscentedKalmanFilter(4, 3, hx=lambda s: s @ H.T, fx=lambda s: s @ F.T, points=MerweScaledSigmaPoints(4))
    ukf.x, ukf.P, ukf.Q, ukf.R = x0.copy(), P0.copy(), Q, R
    for k, (z, obs) in enumerate(zip(zs, observed, strict=True)):
        ukf.predict()
        ukf.update(np.where(obs, z, np.nan), obs)
        np.testing.assert_allclose(ukf.x, ref_x[k], atol=1e-8, err_msg=f"mean at step {k}")
        np.testing.assert_allclose(ukf.P, ref_P[k], atol=1e-8, err_msg=f"covariance at step {k}")


def test_random_walk_predict_is_exact_without_sigma_points(rng: np.random.Generator) -> None:
    ukf = UnscentedKalmanFilter(3, 3, hx=lambda s: s)
    ukf.x, ukf.P, ukf.Q = rng.normal(size=3), np.eye(3) * 2.0, np.eye(3) * 0.5
    ukf.predict()
    np.testing.assert_allclose(ukf.P, np.eye(3) * 2.5)


def test_gated_update_equals_update_when_nothing_is_gated(rng: np.random.Generator) -> None:
    n, m = 5, 6
    H = rng.normal(size=(m, n))
    a = UnscentedKalmanFilter(n, m, hx=lambda s: np.sin(s) @ H.T)
    b = UnscentedKalmanFilter(n, m, hx=lambda s: np.sin(s) @ H.T)
    P = rng.normal(size=(n, n))
    for f in (a, b):
        f.x, f.P = rng.normal(size=n) * 0 + 0.1, P @ P.T * 0.01 + np.eye(n) * 0.01
    z = rng.normal(size=m)
    observed = np.array([True, True, True, False, False, False])
    R_diag = np.full(m, 0.05)
    used = a.gated_update(z, observed, R_diag, gate_chi2=1e12)
    b.update(z, observed, R_diag)
    np.testing.assert_array_equal(used, [True, False])
    np.testing.assert_allclose(a.x, b.x, atol=1e-12)
    np.testing.assert_allclose(a.P, b.P, atol=1e-12)
    np.testing.assert_allclose(a.y, b.y, atol=1e-12, err_msg="innovation of the used rows")
    np.testing.assert_allclose(a.S, b.S, atol=1e-12, err_msg="innovation covariance of the used rows")
    assert a.log_likelihood == pytest.approx(b.log_likelihood, abs=1e-9)


def test_gated_update_drops_an_improbable_joint(rng: np.random.Generator) -> None:
    kf = UnscentedKalmanFilter(6, 6, hx=lambda s: s)
    kf.x, kf.P = np.zeros(6), np.eye(6) * 1e-4
    z = np.zeros(6)
    z[3:] = 5.0  # second joint 5 m off
    used = kf.gated_update(z, np.ones(6, bool), np.full(6, 1e-4), gate_chi2=30.0)
    np.testing.assert_array_equal(used, [True, False])
    assert np.abs(kf.x).max() < 1e-9, "the gated joint moved the state"
    assert kf.y.shape == (3,) and kf.S.shape == (3, 3), "y and S are those of the joint used"


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_gated_update_declares_its_state(seed: int) -> None:
    """x_prior, P_prior: the state it started from; y, S and log_likelihood = log N(y; 0, S) of the rows used."""
    from scipy.stats import multivariate_normal

    rng = np.random.default_rng(seed)
    n, m = 4, 6
    H = rng.normal(size=(m, n))
    kf = UnscentedKalmanFilter(n, m, hx=lambda s: np.tanh(s) @ H.T)
    A = rng.normal(size=(n, n))
    kf.x, kf.P = rng.normal(size=n) * 0.1, A @ A.T * 0.01 + np.eye(n) * 0.01
    x0, P0 = kf.x.copy(), kf.P.copy()
    z = np.tanh(kf.x) @ H.T + rng.normal(size=m) * 0.1
    kf.gated_update(z, np.ones(m, bool), np.full(m, 0.02), gate_chi2=1e12)
    np.testing.assert_array_equal(kf.x_prior, x0)
    np.testing.assert_array_equal(kf.P_prior, P0)
    assert kf.y.shape == (m,) and kf.S.shape == (m, m)
    expected = multivariate_normal(mean=np.zeros(m), cov=kf.S).logpdf(kf.y)
    assert kf.log_likelihood == pytest.approx(expected, rel=1e-10), f"seed {seed}"
    kf.gated_update(np.full(m, np.nan), np.zeros(m, bool), np.full(m, 0.02), gate_chi2=1e12)
    assert kf.y.shape == (0,) and kf.S.shape == (0, 0) and kf.log_likelihood == 0.0, "nothing observed: nothing used"


def test_a_covariance_that_is_not_positive_definite_is_an_internal_fault() -> None:
    """P with a negative eigenvalue (no jitter helps) raises NotPositiveDefinite, a ProcessingError and not a
    ValueError (bad input); x and P stay as they were."""
    kf = UnscentedKalmanFilter(3, 3, hx=lambda s: s)
    kf.x, kf.P = np.zeros(3), np.diag([1.0, -1.0, 1.0])
    with pytest.raises(NotPositiveDefinite, match="covariance P") as caught:
        kf.gated_update(np.ones(3), np.ones(3, bool), np.full(3, 0.1), gate_chi2=30.0)
    assert isinstance(caught.value, ProcessingError) and not isinstance(caught.value, ValueError)
    np.testing.assert_array_equal(kf.P, np.diag([1.0, -1.0, 1.0]))


def test_an_innovation_covariance_that_is_not_positive_definite_is_reported_with_lapacks_info() -> None:
    """R with a negative variance makes S indefinite: potrf's info is checked, not ignored."""
    kf = UnscentedKalmanFilter(3, 3, hx=lambda s: s)
    kf.x, kf.P = np.zeros(3), np.eye(3) * 0.01
    x0 = kf.x.copy()
    with pytest.raises(NotPositiveDefinite, match="innovation covariance S") as caught:
        kf.gated_update(np.zeros(3), np.ones(3, bool), np.array([0.1, 0.1, -1.0]), gate_chi2=np.inf, group=1)
    assert caught.value.info == 3, "the third leading minor is the first that is not positive"
    np.testing.assert_array_equal(kf.x, x0)
    with pytest.raises(NotPositiveDefinite, match="innovation covariance S"):
        kf.update(np.zeros(3), np.ones(3, bool), np.array([0.1, 0.1, -1.0]))


def _rts(xs, Ps, F, Q):
    xs, Ps = xs.copy(), Ps.copy()
    for k in range(len(xs) - 2, -1, -1):
        Pp = F @ Ps[k] @ F.T + Q
        C = Ps[k] @ F.T @ np.linalg.inv(Pp)
        xs[k] = xs[k] + C @ (xs[k + 1] - F @ xs[k])
        Ps[k] = Ps[k] + C @ (Ps[k + 1] - Pp) @ C.T
    return xs, Ps


@pytest.mark.parametrize("linear_fx", [False, True])
def test_unscented_rts_equals_linear_rts(rng: np.random.Generator, linear_fx: bool) -> None:
    F, H, Q, R, zs, observed = _linear_problem(rng, steps=25)
    if not linear_fx:
        F = np.eye(4)
    xs, Ps = _kalman(F, H, Q, R, zs, observed, np.zeros(4), np.eye(4))
    ref_x, ref_P = _rts(xs, Ps, F, Q)
    got_x, got_P = unscented_rts(xs, Ps, Q, (lambda s: s @ F.T) if linear_fx else None)
    np.testing.assert_allclose(got_x, ref_x, atol=1e-8)
    np.testing.assert_allclose(got_P, ref_P, atol=1e-8)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_unscented_rts_with_a_noise_scale_per_step_equals_the_stacked_noise(seed: int) -> None:
    """q_scale (T,) with one Q (n, n) gives the very numbers of Qs[k] = q_scale[k] · Q stacked (T, n, n)."""
    rng = np.random.default_rng(seed)
    F, H, Q, R, zs, observed = _linear_problem(rng, steps=30)
    xs, Ps = _kalman(np.eye(4), H, Q, R, zs, observed, np.zeros(4), np.eye(4))
    scale = rng.uniform(0.5, 2.0, len(xs))
    got_x, got_P = unscented_rts(xs, Ps, Q, q_scale=scale)
    ref_x, ref_P = unscented_rts(xs, Ps, np.einsum("t,ij->tij", scale, Q))
    np.testing.assert_array_equal(got_x, ref_x)
    np.testing.assert_array_equal(got_P, ref_P)


def _filtered_estimates(rng: np.random.Generator, T: int, n: int = 36) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Returns random means xs (T, n), symmetric positive definite covariances Ps (T, n, n) and a diagonal Q (n, n)
    for the smoother, at the pipeline's state size by default."""
    A = 0.1 * rng.normal(size=(T, n, n))
    Ps = A @ np.swapaxes(A, 1, 2) + 1e-3 * np.eye(n)
    Ps = 0.5 * (Ps + np.swapaxes(Ps, 1, 2))
    xs = rng.normal(size=(T, n))
    return xs, Ps, np.diag(rng.uniform(1e-4, 1e-2, n))


@pytest.mark.skipif(not _rts_numba.AVAILABLE, reason="needs numba and numpy's OpenBLAS")
@pytest.mark.parametrize("seed", [1, 2, 3])
@pytest.mark.parametrize("scaled", [True, False])
def test_compiled_random_walk_smoother_equals_numpys_bit_for_bit(seed: int, scaled: bool) -> None:
    """The compiled loop (_rts_numba) gives numpy's loop's very numbers, on the pipeline's state size (36)."""
    rng = np.random.default_rng(seed)
    T = 200
    xs, Ps, Q = _filtered_estimates(rng, T)
    scale = rng.uniform(0.5, 2.0, T) if scaled else None
    ref_x, ref_P = unscented_rts(xs, Ps, Q, q_scale=scale, compiled=False)
    got_x, got_P = unscented_rts(xs, Ps, Q, q_scale=scale, compiled=True)
    np.testing.assert_array_equal(got_x, ref_x)
    np.testing.assert_array_equal(got_P, ref_P)
    assert not np.array_equal(ref_P, Ps)  # it smoothed something


@pytest.mark.parametrize("compiled", [True, False])
def test_smoothing_the_means_only_gives_the_same_means_and_leaves_the_covariances_filtered(compiled: bool) -> None:
    """covariances=False (pipeline.filter_recording): the gain needs only the filtered covariances, so the means are
    the full smoother's bit for bit and Ps comes back as it went in."""
    rng = np.random.default_rng(4)
    T = 150
    xs, Ps, Q = _filtered_estimates(rng, T)
    scale = rng.uniform(0.5, 2.0, T)
    ref_x, ref_P = unscented_rts(xs, Ps, Q, q_scale=scale, compiled=compiled)
    got_x, got_P = unscented_rts(xs, Ps, Q, q_scale=scale, compiled=compiled, covariances=False)
    np.testing.assert_array_equal(got_x, ref_x)
    np.testing.assert_array_equal(got_P, Ps)
    assert not np.array_equal(got_x, xs) and not np.array_equal(ref_P, Ps)  # both smoothed something


def test_unscented_rts_refuses_a_noise_scale_of_the_wrong_length() -> None:
    xs, Ps = np.zeros((5, 2)), np.broadcast_to(np.eye(2), (5, 2, 2))
    with pytest.raises(ValueError, match=r"q_scale needs Qs \(2, 2\) and shape \(5,\), got \(2, 2\) and \(4,\)"):
        unscented_rts(xs, Ps, np.eye(2), q_scale=np.ones(4))


@pytest.mark.parametrize("compiled", [True, False])
@pytest.mark.parametrize("scaled", [True, False])
def test_unscented_rts_reports_a_predicted_covariance_that_is_not_positive_definite(
    compiled: bool, scaled: bool
) -> None:
    xs, Ps = np.zeros((3, 2)), np.broadcast_to(-np.eye(2), (3, 2, 2)).copy()
    scale = np.ones(3) if scaled else None
    with pytest.raises(NotPositiveDefinite, match=r"predicted covariance of frame 2 in the smoother \(2, 2\)"):
        unscented_rts(xs, Ps, 0.1 * np.eye(2), q_scale=scale, compiled=compiled)


def test_combine_information_is_the_information_form(rng: np.random.Generator) -> None:
    A, B = rng.normal(size=(2, 4, 4))
    Pa, Pb = A @ A.T + np.eye(4), B @ B.T + np.eye(4)
    xa, xb = rng.normal(size=(2, 4))
    x, P = combine_information(xa, Pa, xb, Pb)
    P_ref = np.linalg.inv(np.linalg.inv(Pa) + np.linalg.inv(Pb))
    np.testing.assert_allclose(P, P_ref, atol=1e-10)
    np.testing.assert_allclose(x, P_ref @ (np.linalg.solve(Pa, xa) + np.linalg.solve(Pb, xb)), atol=1e-10)


def test_update_checks_the_measurement_shape() -> None:
    kf = UnscentedKalmanFilter(2, 3, hx=lambda s: np.concatenate((s, s[:, :1]), axis=1))
    with pytest.raises(ValueError, match=r"z must have shape \(3,\), got \(2,\)"):
        kf.update(np.zeros(2))
