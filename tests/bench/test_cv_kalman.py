"""Constant-velocity Kalman filter + RTS smoother: a hand-computed case, the batch least-squares identity, noise
estimation from the data."""

import numpy as np

from bench.baselines.cv_kalman import cv_kalman_rts, measurement_sd


def test_no_process_noise_gives_the_least_squares_line() -> None:
    # q = 0 and a vague prior: the smoother is the least-squares line through (0, 0), (1, 1), (2, 3):
    # slope 3/2, intercept -1/6, fitted values -1/6, 4/3, 17/6 (hand computed).
    t = np.array([0.0, 1.0, 2.0])
    z = np.array([[0.0], [1.0], [3.0]])
    y = cv_kalman_rts(t, z, q=0.0, r=1.0, P0=np.diag([1e10, 1e10]))
    np.testing.assert_allclose(y[:, 0], [-1 / 6, 4 / 3, 17 / 6], atol=1e-5, err_msg="LS line")


def test_matches_batch_generalised_least_squares() -> None:
    # The RTS smoother is the MAP estimate of the linear-Gaussian model: solve it as one least-squares problem.
    rng = np.random.default_rng(1)
    T, dt, q, r = 12, 0.1, 2.0, 0.05
    t = np.arange(T) * dt
    z = np.cumsum(rng.standard_normal(T)) * 0.05
    z[5] = np.nan
    P0 = np.diag([0.3, 0.7])
    F = np.array([[1, dt], [0, 1]])
    Q = q * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
    # Unknowns s_0..s_{T-1} (2T); residual blocks whitened by the Cholesky factors of their covariances.
    rows, rhs = [], []
    s0 = np.array([z[0], 0.0])
    W0 = np.linalg.inv(np.linalg.cholesky(P0))
    A = np.zeros((2, 2 * T))
    A[:, :2] = W0
    rows.append(A)
    rhs.append(W0 @ s0)
    Wq = np.linalg.inv(np.linalg.cholesky(Q))
    for k in range(1, T):
        A = np.zeros((2, 2 * T))
        A[:, 2 * k : 2 * k + 2] = Wq
        A[:, 2 * k - 2 : 2 * k] = -Wq @ F
        rows.append(A)
        rhs.append(np.zeros(2))
    for k in range(T):
        if np.isfinite(z[k]):
            A = np.zeros((1, 2 * T))
            A[0, 2 * k] = 1 / r
            rows.append(A)
            rhs.append(np.array([z[k] / r]))
    sol = np.linalg.lstsq(np.vstack(rows), np.concatenate(rhs), rcond=None)[0]
    y = cv_kalman_rts(t, z[:, None], q=q, r=r, P0=P0)
    np.testing.assert_allclose(y[:, 0], sol[0::2], atol=1e-9, err_msg="RTS vs batch GLS")


def test_measurement_sd_from_second_differences() -> None:
    rng = np.random.default_rng(2)
    t = np.arange(3000) / 30.0
    x = 0.2 * np.sin(2 * np.pi * 0.3 * t)[:, None] + 0.01 * rng.standard_normal((3000, 1))
    x[::50] += 1.0  # outliers must not inflate the estimate
    np.testing.assert_allclose(measurement_sd(x), 0.01, rtol=0.1)


def test_estimated_noise_reduces_error() -> None:
    rng = np.random.default_rng(3)
    t = np.arange(900) / 30.0
    x = 0.3 * np.sin(2 * np.pi * 0.4 * t)[:, None, None] * np.ones((1, 2, 3))
    z = x + 0.01 * rng.standard_normal(x.shape)
    y = cv_kalman_rts(t, z)
    assert np.sqrt(np.mean((y - x) ** 2)) < 0.5 * np.sqrt(np.mean((z - x) ** 2))
