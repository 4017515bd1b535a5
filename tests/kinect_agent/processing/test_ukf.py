"""The UKF core against a linear Kalman filter on a linear problem, and the smoother/combination helpers."""

from __future__ import annotations

import numpy as np
import pytest

from kinect_agent.processing.ukf import (
    MerweScaledSigmaPoints,
    UnscentedKalmanFilter,
    combine_information,
    gated_update,
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
    x, zs = np.array([0.0, 0.0, 1.0, -0.5]), []
    for _ in range(steps):
        x = F @ x + rng.multivariate_normal(np.zeros(4), Q)
        zs.append(H @ x + rng.multivariate_normal(np.zeros(3), R))
    zs = np.array(zs)
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
    used = gated_update(a, z, observed, R_diag, gate_chi2=1e12)
    b.update(z, observed, R_diag)
    np.testing.assert_array_equal(used, [True, False])
    np.testing.assert_allclose(a.x, b.x, atol=1e-12)
    np.testing.assert_allclose(a.P, b.P, atol=1e-12)


def test_gated_update_drops_an_improbable_joint(rng: np.random.Generator) -> None:
    kf = UnscentedKalmanFilter(6, 6, hx=lambda s: s)
    kf.x, kf.P = np.zeros(6), np.eye(6) * 1e-4
    z = np.zeros(6)
    z[3:] = 5.0  # second joint 5 m off
    used = gated_update(kf, z, np.ones(6, bool), np.full(6, 1e-4), gate_chi2=30.0)
    np.testing.assert_array_equal(used, [True, False])
    assert np.abs(kf.x).max() < 1e-9, "the gated joint moved the state"


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
