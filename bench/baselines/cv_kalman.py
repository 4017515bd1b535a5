"""Constant-velocity Kalman filter with Rauch-Tung-Striebel smoother, per coordinate, noise from the data.

Reference: Y. Bar-Shalom, X. R. Li, T. Kirubarajan, "Estimation with Applications to Tracking and Navigation"
(2001), §6.2.2 (continuous white-noise acceleration model) and §8.6 (RTS fixed-interval smoother); H. E. Rauch,
F. Tung, C. T. Striebel, AIAA J. 3(8), 1965. Each coordinate of each joint is a scalar signal with state
s = [p (m), v (m/s)]:
    s_k = F s_{k−1} + w,  F = [[1, dt], [0, 1]],  Q = q·[[dt³/3, dt²/2], [dt²/2, dt]]  (q: m²/s³)
    z_k = p_k + ε,        R = r²
Missing samples (NaN) skip the update. Noise from the data, per coordinate:
    r = 1.4826·MAD(Δ²z)/√6 (second differences of white noise have variance 6r²; the MAD ignores outliers),
    q = the value of a log grid (1e-4 … 1e2 m²/s³) that maximises the innovation log-likelihood, each squared
        normalised innovation capped at 25 so that tracking-loss bursts do not choose q.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from bench.baselines._common import check_input

Q_GRID = np.logspace(-4, 2, 19)  # m²/s³
R_FLOOR_M = 0.001
INNOVATION_CAP = 25.0


def measurement_sd(x: np.ndarray) -> np.ndarray:
    """Returns r (C,) m: the robust SD of white measurement noise from second differences of x (T, C) m."""
    d2 = x[2:] - 2.0 * x[1:-1] + x[:-2]
    with np.errstate(all="ignore"):
        med = np.nanmedian(d2, axis=0)
        mad = np.nanmedian(np.abs(d2 - med), axis=0)
    r = 1.4826 * mad / np.sqrt(6.0)
    return np.maximum(np.nan_to_num(r, nan=R_FLOOR_M), R_FLOOR_M)


def _transition(dt: float) -> tuple[np.ndarray, np.ndarray]:
    F = np.array([[1.0, dt], [0.0, 1.0]])
    Qu = np.array([[dt**3 / 3.0, dt**2 / 2.0], [dt**2 / 2.0, dt]])
    return F, Qu


def _initial(x: np.ndarray, r: np.ndarray, P0: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """Returns s0 (C, 2) at the first finite sample of each channel, and P0 (C, 2, 2)."""
    C = x.shape[1]
    first = np.argmax(np.isfinite(x), axis=0)
    s0 = np.zeros((C, 2))
    s0[:, 0] = np.nan_to_num(x[first, np.arange(C)])
    if P0 is None:
        P = np.zeros((C, 2, 2))
        P[:, 0, 0] = np.maximum(r**2, 1e-6) * 4.0
        P[:, 1, 1] = 1.0  # (1 m/s)²
    else:
        P = np.broadcast_to(np.asarray(P0, dtype=np.float64), (C, 2, 2)).copy()
    return s0, P


@dataclass(frozen=True)
class ForwardPass:
    """A forward pass of the CV Kalman filter: predicted and filtered states (T, C, 2) [m, m/s] and covariances
    (T, C, 2, 2), and the (capped) innovation log-likelihood (C,) per channel."""

    s_pred: np.ndarray
    P_pred: np.ndarray
    s_filt: np.ndarray
    P_filt: np.ndarray
    loglik: np.ndarray


def kalman_forward(
    t: np.ndarray, x: np.ndarray, q: np.ndarray, r: np.ndarray, P0: np.ndarray | None = None
) -> ForwardPass:
    """Runs the CV Kalman filter over x (T, C) m with q (C,) m²/s³ and r (C,) m; returns every step's states.

    P0: (2, 2) or (C, 2, 2) initial covariance (default: 4r² and (1 m/s)²) at the first frame.
    """
    T, C = x.shape
    arrays = [np.empty((T, C, 2)), np.empty((T, C, 2, 2)), np.empty((T, C, 2)), np.empty((T, C, 2, 2))]
    ll = _filter(t, x, q, r, P0, arrays)
    s_pred, P_pred, s_filt, P_filt = arrays
    return ForwardPass(s_pred, P_pred, s_filt, P_filt, ll)


def kalman_loglik(
    t: np.ndarray, x: np.ndarray, q: np.ndarray, r: np.ndarray, P0: np.ndarray | None = None
) -> np.ndarray:
    """Returns the (capped) innovation log-likelihood (C,) of the CV Kalman filter over x (T, C) m (as
    kalman_forward, without keeping the states)."""
    return _filter(t, x, q, r, P0, None)


def _filter(
    t: np.ndarray, x: np.ndarray, q: np.ndarray, r: np.ndarray, P0: np.ndarray | None, arrays: list[np.ndarray] | None
) -> np.ndarray:
    """Runs the filter; writes s_pred, P_pred, s_filt, P_filt into `arrays` unless None; returns loglik (C,)."""
    T, C = x.shape
    s, P = _initial(x, r, P0)
    R = r**2
    ll = np.zeros(C)
    for k in range(T):
        if k:
            F, Qu = _transition(float(t[k] - t[k - 1]))
            s = s @ F.T
            P = F @ P @ F.T + q[:, None, None] * Qu
        if arrays is not None:
            arrays[0][k], arrays[1][k] = s, P
        z = x[k]
        ok = np.isfinite(z)
        S = P[:, 0, 0] + R
        nu = np.where(ok, z - s[:, 0], 0.0)
        K = P[:, :, 0] / S[:, None]  # (C, 2)
        s = np.where(ok[:, None], s + K * nu[:, None], s)
        P_upd = P - K[:, :, None] * P[:, None, 0, :]
        P = np.where(ok[:, None, None], 0.5 * (P_upd + np.swapaxes(P_upd, 1, 2)), P)
        ll += np.where(ok & (k > 0), -0.5 * (np.log(2.0 * np.pi * S) + np.minimum(nu**2 / S, INNOVATION_CAP)), 0.0)
        if arrays is not None:
            arrays[2][k], arrays[3][k] = s, P
    return ll


def rts_smooth(
    t: np.ndarray, s_pred: np.ndarray, P_pred: np.ndarray, s_filt: np.ndarray, P_filt: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Returns the RTS-smoothed states (T, C, 2) and covariances (T, C, 2, 2) from a forward pass."""
    T = s_filt.shape[0]
    s_s, P_s = s_filt.copy(), P_filt.copy()
    for k in range(T - 2, -1, -1):
        F, _ = _transition(float(t[k + 1] - t[k]))
        Pp = P_pred[k + 1]
        det = Pp[:, 0, 0] * Pp[:, 1, 1] - Pp[:, 0, 1] * Pp[:, 1, 0]
        inv = np.stack([np.stack([Pp[:, 1, 1], -Pp[:, 0, 1]], -1), np.stack([-Pp[:, 1, 0], Pp[:, 0, 0]], -1)], 1)
        inv /= det[:, None, None]
        G = P_filt[k] @ F.T @ inv  # (C, 2, 2)
        s_s[k] = s_filt[k] + np.einsum("cij,cj->ci", G, s_s[k + 1] - s_pred[k + 1])
        P_s[k] = P_filt[k] + G @ (P_s[k + 1] - Pp) @ np.swapaxes(G, 1, 2)
    return s_s, P_s


def choose_q(t: np.ndarray, x: np.ndarray, r: np.ndarray, grid: np.ndarray = Q_GRID) -> np.ndarray:
    """Returns q (C,) m²/s³: per channel of x (T, C), the grid value of maximum (capped) innovation likelihood."""
    C, G = x.shape[1], len(grid)
    xx = np.repeat(x, G, axis=1)  # channel-major: channel c, grid g at c·G + g
    qq = np.tile(grid, C)
    ll = kalman_loglik(t, xx, qq, np.repeat(r, G))
    return grid[np.argmax(ll.reshape(C, G), axis=1)]


def cv_kalman_rts(
    t: np.ndarray,
    positions: np.ndarray,
    q: float | np.ndarray | None = None,
    r: float | np.ndarray | None = None,
    P0: np.ndarray | None = None,
) -> np.ndarray:
    """Returns RTS-smoothed positions (T, ...) m (every frame filled) from positions (T, ...) m, NaN = missing.

    t: (T,) s. q: m²/s³ and r: m, scalars or per coordinate (C,); None = estimated from the data (module doc).
    A coordinate without any sample stays NaN.
    """
    shape = np.shape(positions)
    t, x = check_input(t, positions)
    C = x.shape[1]
    r_arr = measurement_sd(x) if r is None else np.broadcast_to(np.asarray(r, dtype=np.float64), (C,)).copy()
    q_arr = choose_q(t, x, r_arr) if q is None else np.broadcast_to(np.asarray(q, dtype=np.float64), (C,)).copy()
    if np.any(r_arr <= 0) or np.any(q_arr < 0):
        raise ValueError("r must be > 0 m and q >= 0 m²/s³")
    fwd = kalman_forward(t, x, q_arr, r_arr, P0)
    s_s, _ = rts_smooth(t, fwd.s_pred, fwd.P_pred, fwd.s_filt, fwd.P_filt)
    out = s_s[..., 0]
    out[:, ~np.isfinite(x).any(axis=0)] = np.nan
    return out.reshape(shape)
