"""Unscented Kalman filter and unscented RTS smoother, vectorised over sigma points (filterpy-style API).

Method: Julier & Uhlmann's unscented transform with van der Merwe's scaled sigma points (filterpy's
MerweScaledSigmaPoints weights), Wan & van der Merwe's UKF, and Särkkä's unscented Rauch-Tung-Striebel smoother
(S. Särkkä, "Unscented Rauch-Tung-Striebel smoother", IEEE TAC 2008). Used by the four-pass kinematic filter of
Wang et al. (section 4), see kinect_agent.processing.pipeline.

Differences from filterpy: fx and hx take all sigma points at once, `fx(sigmas (S, n)) -> (S, n)` and
`hx(sigmas (S, n)) -> (S, m)`; `update(z, observed)` accepts any subset of the observation rows (missing joints),
with R given as a full (m, m) matrix or its diagonal (m,); `fx=None` means the random walk x(t) = x(t−1) + δ(t),
whose unscented transform is exact, so predict() is then x, P + Q without sigma points.

A covariance that is not positive definite where it must be raises processing.errors.NotPositiveDefinite (an
internal fault, not bad input); every factorisation's outcome is checked.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.linalg import cho_factor, cho_solve
from scipy.linalg.lapack import dpotrf as _potrf
from scipy.linalg.lapack import dpotrs as _potrs

from kinect_agent.processing import _rts_numba
from kinect_agent.processing.errors import LapackFailed, NotPositiveDefinite

Fn = Callable[[np.ndarray], np.ndarray]


class MerweScaledSigmaPoints:
    """Van der Merwe's scaled sigma points: 2n+1 points, weights Wm (2n+1,) and Wc (2n+1,) as in filterpy."""

    def __init__(self, n: int, alpha: float = 0.5, beta: float = 2.0, kappa: float = 0.0) -> None:
        if n < 1:
            raise ValueError(f"state dimension must be >= 1, got {n}")
        self.n, self.alpha, self.beta, self.kappa = n, alpha, beta, kappa
        lam = alpha**2 * (n + kappa) - n
        self.scale = float(np.sqrt(n + lam))
        self.Wm = np.full(2 * n + 1, 0.5 / (n + lam))
        self.Wc = self.Wm.copy()
        self.Wm[0] = lam / (n + lam)
        self.Wc[0] = lam / (n + lam) + (1.0 - alpha**2 + beta)

    def num_sigmas(self) -> int:
        """Returns 2n + 1."""
        return 2 * self.n + 1

    def sigma_points(self, x: np.ndarray, P: np.ndarray) -> np.ndarray:
        """Returns sigma points (2n+1, n) for mean x (n,) and covariance P (n, n): x, x + c·L_i, x − c·L_i."""
        L = safe_cholesky(P) * self.scale
        sig = np.empty((2 * self.n + 1, self.n))
        sig[0] = x
        sig[1 : self.n + 1] = x + L.T
        sig[self.n + 1 :] = x - L.T
        return sig


def safe_cholesky(P: np.ndarray) -> np.ndarray:
    """Returns lower-triangular L with L L^T = P; symmetrises and adds growing jitter if P is not quite positive."""
    try:
        return np.linalg.cholesky(P)
    except np.linalg.LinAlgError:
        S = 0.5 * (P + P.T)
        jitter = 1e-12 * max(float(np.trace(S)) / len(S), 1e-12)
        for _ in range(12):
            try:
                return np.linalg.cholesky(S + jitter * np.eye(len(S)))
            except np.linalg.LinAlgError:
                jitter *= 10.0
        raise NotPositiveDefinite(f"covariance P {P.shape}, even with jitter up to {jitter / 10.0:.1e},") from None


class UnscentedKalmanFilter:
    """UKF with filterpy's attributes x (n,), P (n, n), Q (n, n), R (m, m) and predict()/update(z)/gated_update().

    fx: (S, n) -> (S, n) state transition on all sigma points, or None for the random walk (identity).
    hx: (S, n) -> (S, m) observation function on all sigma points.

    What an update leaves, as filterpy does: x_prior (n,), P_prior (n, n) the state it started from; y (k,) the
    innovation of the k rows it used and S (k, k) their innovation covariance (k = 0: nothing was observed or
    everything was gated); log_likelihood, log N(y; 0, S) (0.0 when k = 0).
    """

    def __init__(
        self,
        dim_x: int,
        dim_z: int,
        hx: Fn,
        fx: Fn | None = None,
        points: MerweScaledSigmaPoints | None = None,
    ) -> None:
        self.dim_x, self.dim_z = dim_x, dim_z
        self.fx, self.hx = fx, hx
        self.points = points or MerweScaledSigmaPoints(dim_x)
        if self.points.n != dim_x:
            raise ValueError(f"sigma points are for n={self.points.n}, but dim_x={dim_x}")
        self.x = np.zeros(dim_x)
        self.P = np.eye(dim_x)
        self.Q = np.eye(dim_x)
        self.R = np.eye(dim_z)
        self.x_prior = self.x.copy()
        self.P_prior = self.P.copy()
        self.y = np.zeros(0)
        self.S = np.zeros((0, 0))
        self.log_likelihood = 0.0

    def _begin_update(self) -> None:
        """Keeps the state the update starts from and clears what the last update left (nothing used yet)."""
        self.x_prior = self.x.copy()
        self.P_prior = self.P.copy()
        self.y = np.zeros(0)
        self.S = np.zeros((0, 0))
        self.log_likelihood = 0.0

    def predict(self, Q: np.ndarray | None = None) -> None:
        """Propagates x, P one step: through fx by the unscented transform, or x, P + Q for the random walk."""
        Q = self.Q if Q is None else Q
        if self.fx is None:
            self.P = self.P + Q
            return
        sig = self.points.sigma_points(self.x, self.P)
        fs = self.fx(sig)
        x = self.points.Wm @ fs
        d = fs - x
        self.x = x
        self.P = (d.T * self.points.Wc) @ d + Q

    def update(self, z: np.ndarray, observed: np.ndarray | None = None, R: np.ndarray | None = None) -> None:
        """Corrects x, P with measurement z (m,); rows where `observed` (m,) bool is False are ignored (may be NaN).

        R: (m, m) or its diagonal (m,) for this step (default self.R). No observed row: nothing changes.
        """
        z = np.asarray(z, dtype=np.float64)
        if z.shape != (self.dim_z,):
            raise ValueError(f"z must have shape ({self.dim_z},), got {z.shape}")
        obs = np.isfinite(z) if observed is None else np.asarray(observed, dtype=bool) & np.isfinite(z)
        self._begin_update()
        if not obs.any():
            return
        R = self.R if R is None else np.asarray(R, dtype=np.float64)
        R_obs = np.diag(R[obs]) if R.ndim == 1 else R[np.ix_(obs, obs)]
        sig = self.points.sigma_points(self.x, self.P)
        Z = self.hx(sig)[:, obs]
        self._correct(sig, Z, z[obs], R_obs)

    def _correct(self, sig: np.ndarray, Z: np.ndarray, z: np.ndarray, R_obs: np.ndarray) -> None:
        Wm, Wc = self.points.Wm, self.points.Wc
        zp = Wm @ Z
        dz = Z - zp
        dx = sig - self.x
        dzw = dz.T * Wc
        S = dzw @ dz + R_obs
        Pxz = (dx.T * Wc) @ dz
        try:
            cf = cho_factor(S, lower=True, check_finite=False)
        except np.linalg.LinAlgError:
            raise NotPositiveDefinite(f"innovation covariance S {S.shape}") from None
        K = cho_solve(cf, Pxz.T, check_finite=False).T  # (n, m)
        y = z - zp
        self.x = self.x + K @ y
        P = self.P - K @ Pxz.T
        self.P = 0.5 * (P + P.T)
        self.y, self.S = y, S
        self.log_likelihood = _log_likelihood(y, cho_solve(cf, y, check_finite=False), np.diag(cf[0]))

    def gated_update(
        self,
        z: np.ndarray,
        observed: np.ndarray,
        R_diag: np.ndarray,
        gate_chi2: float,
        group: int = 3,
        at_mean: bool = False,
    ) -> np.ndarray:
        """Corrects x, P with z (m,), dropping whole groups of `group` rows (one joint = 3 rows) whose innovation is
        improbable: y_gᵀ S_gg⁻¹ y_g > gate_chi2 (S_gg the group's block of the innovation covariance).

        observed: (m,) bool. R_diag: (m,) variances. Returns (m // group,) bool: the groups that were used.
        at_mean: the innovation is z − h(x̄) (the centre sigma point) instead of z − Σ Wm·h(σ) (PipelineConfig
        .innovation_at_mean); S and Pxz are the same either way.
        One evaluation of hx on the sigma points and one innovation covariance serve both the gate and the update.
        Sets x_prior, P_prior, y, S, log_likelihood (of the rows used). Raises NotPositiveDefinite when P (even with
        jitter), a group's block of S or the kept rows' S cannot be factorised; x and P are then unchanged.
        """
        obs = np.asarray(observed, dtype=bool) & np.isfinite(z)
        groups = obs.reshape(-1, group).all(axis=1)
        self._begin_update()
        if not groups.any():
            return groups
        rows = np.repeat(groups, group)
        pts = self.points
        n = self.dim_x
        L = safe_cholesky(self.P)
        sig = np.empty((2 * n + 1, n))
        sig[0] = self.x
        np.add(self.x, pts.scale * L.T, out=sig[1 : n + 1])
        np.subtract(self.x, pts.scale * L.T, out=sig[n + 1 :])
        Z = self.hx(sig)[:, rows]
        zp = pts.Wm @ Z
        dz = Z - zp
        # S = Σ Wc_i dz_i dz_iᵀ + R (the 2n outer points share one weight).
        S = (dz[1:].T @ dz[1:]) * pts.Wc[1]
        S += pts.Wc[0] * np.outer(dz[0], dz[0])
        S[np.diag_indices_from(S)] += R_diag[rows]
        y = z[rows] - (Z[0] if at_mean else zp)
        g = int(groups.sum())
        ar = np.arange(g)
        blocks = S.reshape(g, group, g, group)[ar, :, ar, :]  # (g, group, group) diagonal blocks
        yg = y.reshape(g, group)
        try:
            d2 = np.einsum("gi,gi->g", yg, np.linalg.solve(blocks, yg[..., None])[..., 0])
        except np.linalg.LinAlgError:
            raise NotPositiveDefinite(f"a block ({group}, {group}) of the innovation covariance S {S.shape}") from None
        ok = d2 <= gate_chi2
        used = groups.copy()
        used[groups] = ok
        if not ok.any():
            return used
        keep = np.repeat(ok, group)
        if not keep.all():
            S = S[np.ix_(keep, keep)]
            dz, y = dz[:, keep], y[keep]
        # Pxz = Σ Wc_i (σ_i − x) dz_iᵀ = c·Wc_1·L (dz₊ − dz₋) since σ_i − x = ±c·L_i (centre term is zero).
        Pxz = (pts.scale * pts.Wc[1]) * (L @ (dz[1 : n + 1] - dz[n + 1 :]))
        cf, info = _potrf(S, lower=0, clean=0)  # S = Uᵀ U
        if info > 0:
            raise NotPositiveDefinite(f"innovation covariance S {S.shape} of the rows kept", info)
        if info < 0:
            raise LapackFailed("dpotrf", info)
        rhs, info = _potrs(cf, np.column_stack([Pxz.T, y]), lower=0)  # S⁻¹ [Pxzᵀ | y]
        if info != 0:
            raise LapackFailed("dpotrs", info)
        Kt, Sinv_y = rhs[:, :n], rhs[:, n]  # Kᵀ = S⁻¹ Pxzᵀ
        self.x = self.x + y @ Kt
        P = self.P - Pxz @ Kt
        self.P = 0.5 * (P + P.T)
        self.y, self.S = y, S
        self.log_likelihood = _log_likelihood(y, Sinv_y, np.diag(cf))
        return used


def _log_likelihood(y: np.ndarray, Sinv_y: np.ndarray, chol_diag: np.ndarray) -> float:
    """Returns log N(y; 0, S) from y (k,), S⁻¹y (k,) and the diagonal (k,) of a Cholesky factor of S."""
    return float(-0.5 * y @ Sinv_y - np.sum(np.log(chol_diag)) - 0.5 * len(y) * np.log(2 * np.pi))


def unscented_rts(
    xs: np.ndarray,
    Ps: np.ndarray,
    Qs: np.ndarray,
    fx: Fn | None = None,
    points: MerweScaledSigmaPoints | None = None,
    q_scale: np.ndarray | None = None,
    overwrite: bool = False,
    compiled: bool = True,
    covariances: bool = True,
) -> tuple[np.ndarray, np.ndarray]:
    """Returns smoothed (xs (T, n), Ps (T, n, n)) from filtered means xs (T, n) and covariances Ps (T, n, n).

    Qs: (T, n, n) or (n, n), the process noise added when stepping from frame k to k+1 (Qs[k]).
    q_scale: (T,) with Qs (n, n): the noise of step k is q_scale[k] · Qs (the same numbers as Qs[k] of a stacked
    (T, n, n) array, without building it: 190 MB for 10 minutes at 30 Hz).
    fx: the transition on sigma points (None: random walk, for which the unscented RTS equals the linear one
    with F = I: gain C = P_k (P_k + Q_k)^-1; computed here through sigma points all the same when fx is given).
    The factorisations call LAPACK directly (dpotrf, dpotrs: what scipy's cho_factor/cho_solve call, without their
    per-call checks, same numbers).
    overwrite: smooth xs and Ps in place (float64, C order) and return them, instead of copies (a 10-minute
    recording's Ps is 190 MB).
    compiled: for the random walk, the loop in one compiled kernel (_rts_numba) when numba and numpy's OpenBLAS are
    there: the same operations, the same results bit for bit; False: numpy's loop.
    covariances: False smooths the means only, for the random walk (the gain C = P_k (P_k + Q_k)⁻¹ needs only the
    filtered covariances, so the means are the same bit for bit); Ps is then returned as given, filtered. Saves two
    (n, n) products per frame. Ignored when fx is given.
    """
    T, n = xs.shape
    if Ps.shape != (T, n, n):
        raise ValueError(f"Ps must have shape ({T}, {n}, {n}), got {Ps.shape}")
    if q_scale is not None and (Qs.shape != (n, n) or np.shape(q_scale) != (T,)):
        raise ValueError(f"q_scale needs Qs ({n}, {n}) and shape ({T},), got {Qs.shape} and {np.shape(q_scale)}")
    pts = points or MerweScaledSigmaPoints(n)
    in_place = overwrite and all(a.dtype == np.float64 and a.flags.c_contiguous for a in (xs, Ps))
    xs_s = xs if in_place else np.array(xs, dtype=np.float64)
    Ps_s = Ps if in_place else np.array(Ps, dtype=np.float64)
    if fx is None and Qs.ndim == 2:
        Q = np.asarray(Qs, dtype=np.float64)
        if compiled and _rts_numba.AVAILABLE:
            _rts_random_walk_compiled(xs_s, Ps_s, Q, q_scale, covariances)
        else:
            _rts_random_walk(xs_s, Ps_s, Q, q_scale, covariances)
        return xs_s, Ps_s
    for k in range(T - 2, -1, -1):
        Q = (Qs if q_scale is None else q_scale[k] * Qs) if Qs.ndim == 2 else Qs[k]
        x, P = xs_s[k], Ps_s[k]
        if fx is None:
            x_pred, P_pred, D = x, P + Q, P
        else:
            sig = pts.sigma_points(x, P)
            fs = fx(sig)
            x_pred = pts.Wm @ fs
            df = fs - x_pred
            P_pred = (df.T * pts.Wc) @ df + Q
            D = ((sig - x).T * pts.Wc) @ df
        C = _smoother_gain(P_pred, D, k)
        xs_s[k] = x + C @ (xs_s[k + 1] - x_pred)
        Pk = P + C @ (Ps_s[k + 1] - P_pred) @ C.T
        Ps_s[k] = 0.5 * (Pk + Pk.T)
    return xs_s, Ps_s


def _smoother_gain(P_pred: np.ndarray, D: np.ndarray, k: int) -> np.ndarray:
    """Returns the RTS gain C = D P_pred⁻¹ (n, n) of step k (P_pred: the predicted covariance of frame k + 1, D: the
    cross covariance), by Cholesky; NotPositiveDefinite or LapackFailed when a factorisation fails."""
    cf, info = _potrf(P_pred, lower=1, clean=0)
    if info > 0:
        raise NotPositiveDefinite(f"predicted covariance of frame {k + 1} in the smoother {P_pred.shape}")
    if info < 0:
        raise LapackFailed("dpotrf", info)
    CT, info = _potrs(cf, D.T, lower=1)
    if info != 0:
        raise LapackFailed("dpotrs", info)
    return CT.T


def _rts_random_walk(
    xs: np.ndarray, Ps: np.ndarray, Q: np.ndarray, q_scale: np.ndarray | None, covariances: bool = True
) -> None:
    """Smooths xs (T, n) and Ps (T, n, n) in place for the random walk (F = I) with noise q_scale[k] · Q (or Q) on
    step k: unscented_rts's loop with fx None, the same operations in the same order into buffers made once (the
    per-step temporaries and their Python cost were a third of the smoother's time). covariances False: the means
    only, Ps left filtered."""
    T, n = xs.shape
    Qk, P_pred, M, CM, Pk = (np.empty((n, n)) for _ in range(5))
    dx, Cdx = np.empty(n), np.empty(n)
    for k in range(T - 2, -1, -1):
        x, P = xs[k], Ps[k]
        if q_scale is None:
            np.add(P, Q, out=P_pred)
        else:
            np.multiply(q_scale[k], Q, out=Qk)
            np.add(P, Qk, out=P_pred)
        C = _smoother_gain(P_pred, P, k)
        np.subtract(xs[k + 1], x, out=dx)
        np.matmul(C, dx, out=Cdx)
        np.add(x, Cdx, out=x)  # xs[k]: x + C (x_{k+1} − x_pred), x_pred = x
        if not covariances:
            continue
        np.subtract(Ps[k + 1], P_pred, out=M)
        np.matmul(C, M, out=CM)
        np.matmul(CM, C.T, out=Pk)
        np.add(P, Pk, out=Pk)  # P + C (P_{k+1} − P_pred) Cᵀ
        np.add(Pk, Pk.T, out=M)
        np.multiply(0.5, M, out=P)  # Ps[k]: symmetrised


def _rts_random_walk_compiled(
    xs: np.ndarray, Ps: np.ndarray, Q: np.ndarray, q_scale: np.ndarray | None, covariances: bool = True
) -> None:
    """_rts_random_walk in _rts_numba's kernel (xs, Ps float64 and C-ordered, smoothed in place); the same errors."""
    Q = np.ascontiguousarray(Q)
    scale = np.zeros(len(xs)) if q_scale is None else np.ascontiguousarray(q_scale, dtype=np.float64)
    status, k, info = _rts_numba.rts_random_walk(xs, Ps, Q, scale, q_scale is not None, covariances)
    if status == _rts_numba.P_PRED_NOT_POSITIVE:
        raise NotPositiveDefinite(f"predicted covariance of frame {k + 1} in the smoother {Q.shape}")
    if status == _rts_numba.POTRF_FAILED:
        raise LapackFailed("dpotrf", int(info))
    if status == _rts_numba.POTRS_FAILED:
        raise LapackFailed("dpotrs", int(info))


def combine_information(
    x_a: np.ndarray, P_a: np.ndarray, x_b: np.ndarray, P_b: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Returns the information-weighted mean of two estimates: P = (P_a⁻¹ + P_b⁻¹)⁻¹, x = P (P_a⁻¹ x_a + P_b⁻¹ x_b).

    x_a, x_b: (..., n); P_a, P_b: (..., n, n). Computed as x = x_a + P_a (P_a + P_b)⁻¹ (x_b − x_a), which needs one
    factorisation and no explicit inverse.
    """
    S = P_a + P_b
    try:
        G = np.linalg.solve(S, np.swapaxes(P_a, -1, -2))  # (P_a + P_b)^-1 P_a^T
    except np.linalg.LinAlgError:
        raise NotPositiveDefinite(f"sum of the two covariances {S.shape}") from None
    G = np.swapaxes(G, -1, -2)  # P_a (P_a + P_b)^-1
    x = x_a + np.einsum("...ij,...j->...i", G, x_b - x_a)
    P = P_a - G @ P_a
    return x, 0.5 * (P + np.swapaxes(P, -1, -2))
