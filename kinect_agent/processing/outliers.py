"""Outlier removal by a Gaussian + uniform mixture per joint (Wang et al., section 3.2), without a reference.

Random error (depth quantisation, systematic error) is Gaussian; tracking loss puts a joint anywhere, i.e. uniform.
At home there is no motion-capture reference, so the mixture p(e) = ρ·N(e; μ, diag σ²) + (1 − ρ)·U(e; box) is fitted
per joint by maximum likelihood (EM) to a 3-D residual e (metres) computed from the recording itself:

    stage 0:  e = p[t, j] − running median of p[·, j] over config.outlier_window_s (0.5 s)
    stage 1+: e = (p[t, j] − q[t, j]) / sqrt(1 + h[t, j]), q a weighted local quadratic fit in time over the same
              window that leaves frame t out, weights 1 − P(outlier) of the previous stage, h its leverage
              (config.outlier_iterations = 2 refinements)

The median survives bursts shorter than half the window but clips turning points; the leave-one-out quadratic
follows turning points and is not pulled by the outliers stage 0 found (why: bench/README.md, "Tuning history of the
pipeline defaults", `outlier_iterations`).
Kinect's own random error sets a floor on σ (config.outlier_min_sigma_m, 15 mm per axis) and the uniform box is at
least config.outlier_min_range_m (1 m) per axis, so that clean stretches cannot make ordinary motion look like
tracking loss. The SDK tracking state enters as a prior: not tracked (0) = missing (probability 1, never used);
tracked (2) and inferred (1) samples get separate mixing weights ρ_2, ρ_1 (both fitted, both ≥ 0.5), so inferred
joints lean towards the outlier component when they misbehave more often. A sample is an outlier when its posterior
probability of the uniform component exceeds config.outlier_threshold: 0.95, not the maximum-a-posteriori 0.5, so
that it "belongs to the uniform component" with confidence. Window and threshold were tuned on simulator + CMU only
(HDM05 held out): bench/README.md, "Tuning history of the pipeline defaults", `outlier_window_s`, `outlier_threshold`.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from kinect_agent.processing import _outliers_numba
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.recording import Recording
from kinect_agent.skeleton import INFERRED, NOT_TRACKED

_SQRT_2PI = np.sqrt(2.0 * np.pi)


@dataclass
class MixtureFit:
    """Maximum-likelihood fit of p(e) = ρ_c·N(e; μ, diag σ²) + (1 − ρ_c)·U(e; box [x1, x2]) for K columns of D-vectors.

    rho: (C, K) Gaussian weight per sample class c (0 = tracked, 1 = inferred). mu, sigma, x1, x2: (K, D) in the
    units of e (the uniform box is the data's bounding box, its maximum-likelihood value). loglik: (K,) final mean
    log-likelihood per sample. n_iter: EM iterations used. n: (K,) samples used per column.
    """

    rho: np.ndarray
    mu: np.ndarray
    sigma: np.ndarray
    x1: np.ndarray
    x2: np.ndarray
    loglik: np.ndarray
    n_iter: int
    n: np.ndarray

    def posterior_uniform(self, e: np.ndarray, cls: np.ndarray | None = None) -> np.ndarray:
        """Returns P(uniform | e), (N, K), for samples e (N, K, D) or (N, K) when D = 1; NaN where e is NaN.

        cls: (N, K) class index of each sample, default 0.
        """
        e = _as_3d(e)
        cls = np.zeros(e.shape[:2], dtype=int) if cls is None else cls
        rho = np.take_along_axis(self.rho, np.clip(cls, 0, len(self.rho) - 1), axis=0)
        g = rho * _normal_pdf(e, self.mu, self.sigma)
        u = (1.0 - rho) / _volume(self.x1, self.x2)
        with np.errstate(invalid="ignore", divide="ignore"):
            return u / (g + u)


def _as_3d(e: np.ndarray) -> np.ndarray:
    e = np.asarray(e, dtype=np.float64)
    return e[..., None] if e.ndim == 2 else e


def _volume(x1: np.ndarray, x2: np.ndarray) -> np.ndarray:
    return np.prod(np.maximum(x2 - x1, 1e-9), axis=-1)


def _normal_pdf(e: np.ndarray, mu: np.ndarray, sigma: np.ndarray) -> np.ndarray:
    """Density of N(mu, diag sigma²) at e (N, K, D); mu, sigma (K, D). Returns (N, K)."""
    zz = np.sum(((e - mu) / sigma) ** 2, axis=-1)
    return np.exp(-0.5 * zz) / (np.prod(sigma, axis=-1) * _SQRT_2PI ** e.shape[-1])


def fit_mixture(
    x: np.ndarray,
    cls: np.ndarray | None = None,
    n_classes: int = 1,
    rho0: float = 0.9,
    max_iter: int = 200,
    tol: float = 1e-9,
    min_sigma: float = 1e-4,
    min_width: float = 0.0,
    min_rho: float = 1e-6,
    compiled: bool = True,
) -> MixtureFit:
    """Fits the Gaussian + uniform mixture to every column of x by EM (maximum likelihood), vectorised over columns.

    x: (N, K) scalars or (N, K, D) vectors (diagonal Gaussian, uniform over the bounding box); NaN = absent.
    cls: (N, K) int class of each sample in [0, n_classes) (each class has its own mixing weight), default all 0.
    min_sigma: lower bound of σ in the units of x, keeps a column of identical values finite.
    min_width: lower bound of each side of the uniform box (centred on the data's box when it is widened): the
    range a tracking loss can throw a joint over, so clean data cannot make the uniform component look narrow.
    min_rho: lower bound of each Gaussian weight ρ_c (e.g. 0.5: outliers are the minority).
    compiled: run each iteration's E step and sums in the compiled kernels (_outliers_numba) when numba is
    installed; the results are the same bit for bit as numpy's (compiled=False), or within rounding (1e-12 relative)
    where numpy uses its own AVX-512 exp and log.
    """
    x = _as_3d(x)
    if x.ndim != 3:
        raise ValueError(f"x must have shape (N, K) or (N, K, D), got {x.shape}")
    N, K, D = x.shape
    cls = np.zeros((N, K), dtype=int) if cls is None else np.asarray(cls, dtype=int)
    if cls.shape != (N, K):
        raise ValueError(f"cls must have shape {(N, K)}, got {cls.shape}")
    ok = np.all(np.isfinite(x), axis=-1)  # (N, K)
    n = ok.sum(axis=0)
    xz = np.where(ok[..., None], x, 0.0)
    xn = np.where(ok[..., None], x, np.nan)
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns give NaN, replaced just below
        x1 = np.nan_to_num(np.nanmin(xn, axis=0), nan=0.0)
        x2 = np.nan_to_num(np.nanmax(xn, axis=0), nan=1.0)
        mu = np.nan_to_num(np.nanmedian(xn, axis=0))
        mad = np.nan_to_num(np.nanmedian(np.abs(xn - mu), axis=0))
    grow = np.maximum(min_width - (x2 - x1), 0.0) / 2.0
    x1, x2 = x1 - grow, x2 + grow
    sigma = np.maximum(1.4826 * mad, min_sigma)
    onehot = np.stack([(cls == c) & ok for c in range(n_classes)])  # (C, N, K)
    n_c = onehot.sum(axis=1)  # (C, K)
    rho = np.full((n_classes, K), rho0)
    vol = _volume(x1, x2)
    prev = np.full(K, -np.inf)
    loglik = prev
    n_iter = 0
    if compiled and _outliers_numba.AVAILABLE:
        return _fit_mixture_compiled(xz, ok, cls, n, n_c, rho, mu, sigma, x1, x2, vol, rho0, max_iter, tol, min_sigma,
                                     min_rho)  # fmt: skip
    for n_iter in range(1, max_iter + 1):  # noqa: B007 - the count is reported
        rho_s = np.einsum("cnk,ck->nk", onehot, rho)
        g = rho_s * _normal_pdf(xz, mu, sigma)
        u = (1.0 - rho_s) / vol
        tot = g + u
        w = np.where(ok, g / np.where(tot > 0, tot, 1.0), 0.0)  # responsibility of the Gaussian (N, K)
        loglik = np.sum(np.where(ok, np.log(np.where(tot > 0, tot, 1e-300)), 0.0), axis=0) / np.maximum(n, 1)
        sw = w.sum(axis=0)[:, None]  # (K, 1)
        rho = np.clip(np.einsum("cnk,nk->ck", onehot, w) / np.maximum(n_c, 1), max(min_rho, 1e-6), 1.0 - 1e-9)
        rho = np.where(n_c > 0, rho, rho0)
        mu = np.where(sw > 0, np.einsum("nk,nkd->kd", w, xz) / np.maximum(sw, 1e-300), mu)
        var = np.einsum("nk,nkd->kd", w, (xz - mu) ** 2) / np.maximum(sw, 1e-300)
        sigma = np.maximum(np.sqrt(np.where(sw > 0, var, sigma**2)), min_sigma)
        if np.all(np.abs(loglik - prev) < tol):
            break
        prev = loglik
    return MixtureFit(rho, mu, sigma, x1, x2, loglik, n_iter, n)


def _fit_mixture_compiled(
    xz: np.ndarray, ok: np.ndarray, cls: np.ndarray, n: np.ndarray, n_c: np.ndarray, rho: np.ndarray, mu: np.ndarray,
    sigma: np.ndarray, x1: np.ndarray, x2: np.ndarray, vol: np.ndarray, rho0: float, max_iter: int, tol: float,
    min_sigma: float, min_rho: float,
) -> MixtureFit:  # fmt: skip
    """fit_mixture's EM loop with the per-sample work in _outliers_numba's kernels; the (K, D) updates are the same
    numpy expressions as fit_mixture's, so the results are the same bit for bit."""
    N, K, D = xz.shape
    xz = np.ascontiguousarray(xz)
    cls = np.ascontiguousarray(np.where((cls >= 0) & (cls < len(rho)), cls, -1))  # -1: in no class (weight 0)
    w = np.empty((N, K))
    rho_sum = np.empty_like(rho)
    mu_sum = np.empty((K, D))
    var_sum = np.empty((K, D))
    norm_d = _SQRT_2PI**D
    prev = np.full(K, -np.inf)
    loglik = prev
    n_iter = 0
    for n_iter in range(1, max_iter + 1):  # noqa: B007 - the count is reported
        norm = np.prod(sigma, axis=-1) * norm_d
        ll, sw_k = _outliers_numba.em_expectation(xz, ok, cls, rho, mu, sigma, norm, vol, w, rho_sum, mu_sum)
        loglik = ll / np.maximum(n, 1)
        sw = sw_k[:, None]
        rho = np.clip(rho_sum / np.maximum(n_c, 1), max(min_rho, 1e-6), 1.0 - 1e-9)
        rho = np.where(n_c > 0, rho, rho0)
        mu = np.where(sw > 0, mu_sum / np.maximum(sw, 1e-300), mu)
        _outliers_numba.em_spread(xz, ok, w, mu, var_sum)
        var = var_sum / np.maximum(sw, 1e-300)
        sigma = np.maximum(np.sqrt(np.where(sw > 0, var, sigma**2)), min_sigma)
        if np.all(np.abs(loglik - prev) < tol):
            break
        prev = loglik
    return MixtureFit(rho, mu, sigma, x1, x2, loglik, n_iter, n)


def _window_frames(rec: Recording, window_s: float) -> int:
    """Returns the odd number of frames covering window_s at the recording's median frame interval (at least 7, so
    that the leave-one-out quadratic has three samples on each side)."""
    dt = float(np.median(np.diff(rec.t))) if rec.n_frames > 1 else 1.0 / 30.0
    w = int(round(window_s / max(dt, 1e-6)))
    return max(7, w | 1)


def running_median(positions: np.ndarray, w: int, compiled: bool = True) -> np.ndarray:
    """Returns the centred running median over w frames (odd) per joint and axis, ignoring NaN.

    positions: (T, J, 3) m, NaN = missing. returns: (T, J, 3) m; NaN where the window holds no sample.
    compiled: a sorted window slid along each series (_outliers_numba) when numba is installed, the same values.
    """
    T = positions.shape[0]
    half = w // 2
    flat = positions.reshape(T, -1)
    pad = np.full((T + 2 * half, flat.shape[1]), np.nan)
    pad[half : half + T] = flat
    if compiled and _outliers_numba.AVAILABLE and T > 0:
        out = np.empty((flat.shape[1], T))
        _outliers_numba.running_median_kernel(np.ascontiguousarray(pad.T), w, out)
        return out.T.reshape(positions.shape)
    win = np.sort(sliding_window_view(pad, w, axis=0), axis=-1)  # NaN sort last; (T, 3J, w)
    cnt = np.sum(np.isfinite(win), axis=-1)
    lo = np.clip((cnt - 1) // 2, 0, w - 1)
    hi = np.clip(cnt // 2, 0, w - 1)
    med = 0.5 * (
        np.take_along_axis(win, lo[..., None], -1)[..., 0] + np.take_along_axis(win, hi[..., None], -1)[..., 0]
    )
    med = np.where(cnt > 0, med, np.nan)
    return med.reshape(positions.shape)


def time_kernel(t: np.ndarray, w: int) -> tuple[np.ndarray, np.ndarray]:
    """Returns (kern (T, w), powers (T, w, 5)): local_quadratic's weights in time for times t (T,) s and a centred
    window of w frames (odd): per frame and window offset the tricube weight (0 at the centre and outside the
    recording) and the powers k⁰..k⁴ of the offset scaled to [-1, 1] (0 outside). Depends on t and w only, so the
    stages of fit() share one (numpy's power of a (T, w, 5) array: 50 ms for 10 minutes at 30 Hz)."""
    T = t.shape[0]
    half = w // 2
    tp = np.full(T + 2 * half, np.nan)
    tp[half : half + T] = t
    dt = sliding_window_view(tp, w) - t[:, None]  # (T, w) s, NaN outside the recording
    span = np.nanmax(np.abs(dt), axis=1, keepdims=True) * (1.0 + 2.0 / w) + 1e-12  # outermost keep some weight
    k = np.nan_to_num(dt / span)  # in [-1, 1]
    kern = np.where(np.isfinite(dt), (1.0 - np.abs(k) ** 3) ** 3, 0.0)
    kern[:, half] = 0.0  # leave the centre frame out
    powers = k[..., None] ** np.arange(5)  # (T, w, 5)
    return kern, powers


def local_quadratic(
    t: np.ndarray,
    positions: np.ndarray,
    weights: np.ndarray,
    w: int,
    compiled: bool = True,
    kernel: tuple[np.ndarray, np.ndarray] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Returns (prediction (T, J, 3) m, leverage (T, J)): a weighted local quadratic fit in time per joint and axis
    over a centred window of w frames (odd), tricube kernel in time, evaluated at the centre frame *without* it.

    t: (T,) s. positions: (T, J, 3) m, NaN = missing. weights: (T, J) in [0, 1] (e.g. 1 − outlier probability).
    leverage h: Var(prediction) = σ²·h for independent noise of SD σ, so the prediction residual has variance
    σ²·(1 + h); it grows near the ends of the recording and around gaps. NaN where the window holds no sample.
    compiled: the window sums and the evaluation in _outliers_numba's kernels when numba is installed (no (T, J, w)
    temporaries), the same values bit for bit. kernel: time_kernel(t, w), when the caller has it already.
    """
    T, J, _ = positions.shape
    half = w // 2
    ok = np.all(np.isfinite(positions), axis=-1)
    wp = np.zeros((T + 2 * half, J))
    wp[half : half + T] = np.where(ok, weights, 0.0)
    yp = np.zeros((T + 2 * half, J, 3))
    yp[half : half + T] = np.where(ok[..., None], positions, 0.0)
    kern, powers = time_kernel(t, w) if kernel is None else kernel
    fast = compiled and _outliers_numba.AVAILABLE and T > 0
    if fast:
        S, S2, B = np.empty((T, J, 5)), np.empty((T, J, 5)), np.empty((T, J, 3, 3))
        _outliers_numba.window_sums(wp, yp, np.ascontiguousarray(kern), np.ascontiguousarray(powers), S, S2, B)
    else:
        Wk = sliding_window_view(wp, w, axis=0) * kern[:, None, :]  # (T, J, w)
        S = np.einsum("tjw,twm->tjm", Wk, powers)
        S2 = np.einsum("tjw,twm->tjm", Wk * Wk, powers)
        B = np.einsum("tjaw,tjw,twm->tjma", sliding_window_view(yp, w, axis=0), Wk, powers[..., :3])  # (T, J, 3, 3)
    idx = np.add.outer(np.arange(3), np.arange(3))
    A = S[..., idx] + 1e-9 * np.eye(3)
    e0 = np.broadcast_to(np.array([1.0, 0.0, 0.0]), A.shape[:-1])
    a = np.linalg.solve(A, e0[..., None])[..., 0]  # first column of A⁻¹ (A symmetric)
    if fast:
        pred, lev = np.empty((T, J, 3)), np.empty((T, J))
        _outliers_numba.quadratic_at_centre(np.ascontiguousarray(a), S2, B, pred, lev)
    else:
        pred = np.einsum("tjm,tjma->tja", a, B)
        lev = np.einsum("tjm,tjmn,tjn->tj", a, S2[..., idx], a)
    enough = S[..., 0] > 1e-6
    return np.where(enough[..., None], pred, np.nan), np.where(enough, np.maximum(lev, 0.0), np.nan)


def _posterior(mix: MixtureFit, e: np.ndarray, cls: np.ndarray) -> np.ndarray:
    return np.nan_to_num(mix.posterior_uniform(e, cls), nan=0.0)


def fit(rec: Recording, config: PipelineConfig | None = None) -> tuple[MixtureFit, np.ndarray, np.ndarray]:
    """Returns (fit, e (T, J, 3), prob (T, J)): the per-joint mixture fitted to the final residuals.

    Stage 0: e = position − running median (window config.outlier_window_s). Stages 1..config.outlier_iterations:
    e = (position − leave-one-out local quadratic prediction weighted by 1 − prob) / sqrt(1 + leverage), which
    follows turning points that a median clips, and which the previous stage's outliers no longer pull.
    """
    config = config or PipelineConfig()
    w = _window_frames(rec, config.outlier_window_s)
    cls = (rec.state == INFERRED).astype(int)
    present = (rec.state != NOT_TRACKED)[..., None]
    e = np.where(present, rec.positions - running_median(rec.positions, w), np.nan)
    floor = config.outlier_min_sigma_m

    def fit(e: np.ndarray) -> MixtureFit:
        return fit_mixture(e, cls, n_classes=2, rho0=0.95, min_sigma=floor, min_width=config.outlier_min_range_m,
                           min_rho=0.5)  # fmt: skip

    mix = fit(e)
    prob = _posterior(mix, e, cls)
    kernel = time_kernel(rec.t, w) if config.outlier_iterations else None
    for _ in range(config.outlier_iterations):
        pred, lev = local_quadratic(rec.t, rec.positions, 1.0 - prob, w, kernel=kernel)
        e = np.where(present, (rec.positions - pred) / np.sqrt(1.0 + lev)[..., None], np.nan)
        mix = fit(e)
        prob = _posterior(mix, e, cls)
    return mix, e, prob


def outlier_probabilities(rec: Recording, config: PipelineConfig | None = None) -> np.ndarray:
    """Returns (T, J) float in [0, 1]: the probability that each joint-frame is a tracking-loss outlier.

    1 where the joint is not tracked (missing).
    """
    if rec.n_frames == 0:
        return np.zeros((0, rec.positions.shape[1]))
    _, _, prob = fit(rec, config)
    prob = np.where(rec.state == NOT_TRACKED, 1.0, prob)
    return np.clip(prob, 0.0, 1.0)


def drop_outliers(rec: Recording, prob: np.ndarray, threshold: float, method: str) -> Recording:
    """Returns a copy of rec whose joint-frames with prob (T, J) > threshold are NaN with state 0, its history
    naming `method` and the count."""
    out = (prob > threshold) & (rec.state != NOT_TRACKED)
    positions = rec.positions.copy()
    positions[out] = np.nan
    state = np.where(out, NOT_TRACKED, rec.state)
    step = f"outliers {method}: {int(out.sum())} joint-frames removed (threshold {threshold})"
    return rec.replace(step=step, positions=positions, state=state)


def remove_outliers(rec: Recording, config: PipelineConfig | None = None) -> tuple[Recording, np.ndarray]:
    """Returns (recording with outliers set to NaN and state 0, prob (T, J)); the input is not changed."""
    config = config or PipelineConfig()
    prob = outlier_probabilities(rec, config)
    return drop_outliers(rec, prob, config.outlier_threshold, "mixture-model v1"), prob
