"""The One Euro filter: a first-order low-pass whose cutoff rises with speed (little jitter at rest, little lag
in motion).

Reference: G. Casiez, N. Roussel, D. Vogel, "1 € Filter: A Simple Speed-based Low-pass Filter for Noisy Input in
Interactive Systems", CHI 2012. Per scalar signal (each joint coordinate), with frame interval Te:
    α(fc) = 1 / (1 + τ/Te), τ = 1 / (2π·fc)
    dx̂_n = α(d_cutoff)·(x_n − x̂_{n−1})/Te + (1 − α(d_cutoff))·dx̂_{n−1}
    fc_n = min_cutoff + β·|dx̂_n|
    x̂_n = α(fc_n)·x_n + (1 − α(fc_n))·x̂_{n−1}          (first sample: x̂ = x, dx̂ = 0)
Parameters for skeletons in metres: min_cutoff 1.5 Hz, β = 0.1 s/m (at 1 m/s — a hand during an exercise — the
cutoff rises to 1.6 Hz; at 10 m/s — a tracking-loss jump — to 2.5 Hz), d_cutoff 1.0 Hz (the paper's value).
Chosen by a grid search of min_cutoff {0.5, 1, 1.5, 2, 3, 4} Hz × β {0, 0.1, 0.3, 1, 3, 10} s/m on simulated
Kinect 2 sessions with seeds bench/accuracy.py does not use (`python bench/accuracy.py --tune-one-euro`, position
RMSE): 117.2 mm here; the grid's best, 116.4 mm, was β = 0 (a fixed 2 Hz first-order low-pass, no longer a One
Euro filter); β ≥ 1 lets the tracking-loss jumps through (≥ 119.9 mm); min_cutoff 0.5 Hz lags (≥ 119.8 mm).
A NaN sample restarts the signal (output NaN, next sample starts afresh).
"""

from __future__ import annotations

import numpy as np

from bench.baselines._common import check_input

MIN_CUTOFF_HZ = 1.5
BETA_S_PER_M = 0.1
D_CUTOFF_HZ = 1.0


def _alpha(cutoff_hz: float | np.ndarray, te: np.ndarray) -> np.ndarray:
    """Returns the smoothing factor for a cutoff (Hz, scalar or per coordinate) over steps te (s, per coordinate)."""
    tau = 1.0 / (2.0 * np.pi * cutoff_hz)
    return 1.0 / (1.0 + tau / te)


def one_euro(
    t: np.ndarray,
    positions: np.ndarray,
    min_cutoff: float = MIN_CUTOFF_HZ,
    beta: float = BETA_S_PER_M,
    d_cutoff: float = D_CUTOFF_HZ,
) -> np.ndarray:
    """Returns One-Euro-filtered positions (T, ...) m, NaN where the input is NaN.

    t: (T,) s, any increasing stamps (Te per step). positions: (T, ...) m; each coordinate is its own signal.
    min_cutoff, d_cutoff: Hz, > 0. beta: s/m, >= 0.
    """
    shape = np.shape(positions)
    t, x = check_input(t, positions)
    if not (min_cutoff > 0 and d_cutoff > 0 and beta >= 0):
        raise ValueError(f"need min_cutoff > 0, d_cutoff > 0, beta >= 0; got {min_cutoff}, {d_cutoff}, {beta}")
    T, C = x.shape
    out = np.full_like(x, np.nan)
    x_hat = np.full(C, np.nan)
    dx_hat = np.zeros(C)
    t_prev = np.full(C, np.nan)
    for n in range(T):
        xn = x[n]
        valid = np.isfinite(xn)
        start = valid & ~np.isfinite(x_hat)
        go = valid & ~start
        te = np.where(go, t[n] - np.where(go, t_prev, t[n] - 1.0), 1.0)
        a_d = _alpha(d_cutoff, te)
        dx = np.where(go, (xn - x_hat) / te, 0.0)
        dx_new = a_d * dx + (1.0 - a_d) * dx_hat
        a = _alpha(min_cutoff + beta * np.abs(dx_new), te)
        filt = a * xn + (1.0 - a) * x_hat
        x_hat = np.where(go, filt, np.where(start, xn, np.nan))
        dx_hat = np.where(go, dx_new, 0.0)
        t_prev = np.where(valid, t[n], np.nan)
        out[n] = x_hat
    return out.reshape(shape)
