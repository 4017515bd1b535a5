"""Per-frame standard deviation of every clinical joint angle from the smoother's state covariance.

The smoothed state of a frame (root (3, m) and the 33 joint angles (rad) of kinematics.ChainModel; the segment
lengths are constants by then) has mean x (36,) and covariance P (36, 36). The clinical angles a = g(x) =
angles.joint_angles(F(x)) (F: forward kinematics) are propagated through sigma points placed one square-root
column step h = √3 either side of the mean, x ± h s_i with P = Σ s_i s_iᵀ, and the mean itself: the second-order
divided difference of Nørgaard, Poulsen and Ravn (2000), a sigma-point rule whose second term keeps the spread of
an angle at a fold (a straight elbow reads flexion ≥ 0 either way, where a first-order rule reads 0):

    d±_i = g(x ± h s_i) − g(x)                                  (wrapped to ±180°)
    SD(a) = sqrt( Σ_i (d+_i − d−_i)² / (4h²) + (h² − 1) / (4h⁴) · Σ_i (d+_i + d−_i)² )

The covariance is computed every `stride` frames and the SD linearly interpolated in between (it varies slowly
except at tracking loss, which lasts 0.07-0.2 s, about a stride). The angles are differences of positions, so the
root position drops out exactly: 2 × 33 + 1 poses of FK + joint_angles per computed frame.

The covariance is the model's: it knows the measurement SD and the random walk, not Kinect's slow AR(1) jitter
(τ ≈ 0.2 s) or its bias, so the raw SDs are overconfident. INFLATION is the factor measured on simulated sessions
with known truth (bench/uncertainty.py; bench/README.md): the SD to report is INFLATION × the model's SD.
"""

from __future__ import annotations

import numpy as np

from kinect_agent.body.angles import ANGLE_NAMES, joint_angles
from kinect_agent.body.kinematics import N_BONES, ChainModel

DEFAULT_STRIDE = 5  # frames between two covariance propagations (6 Hz at 30 Hz)
CHUNK_FRAMES = 256  # computed frames per block (bounds memory: 256 × 67 poses)
# SD of the angle error (its session mean removed) / the model's SD: the median over the angles on the training
# sessions of bench/uncertainty.py (1.78; per angle 0.8-4.2, shoulder rotation 2.9-7.8), bench/README.md.
INFLATION = 1.8
H = float(np.sqrt(3.0))  # sigma-point step in SDs (h² = 3: the Gaussian's kurtosis, Nørgaard et al.)
SD_FLOOR_DEG = 0.1  # no angle is known better than this (rounding of stored positions, FK round-off)


def _square_roots(P: np.ndarray) -> np.ndarray:
    """Returns S (..., n, n) with S Sᵀ = P: the Cholesky factor, or (a block with a factor that fails) the
    eigen-decomposition's columns sqrt(λ_i) v_i with round-off negative eigenvalues read as 0."""
    P = 0.5 * (P + np.swapaxes(P, -1, -2))
    try:
        return np.linalg.cholesky(P)
    except np.linalg.LinAlgError:
        w, V = np.linalg.eigh(P)
        return V * np.sqrt(np.clip(w, 0.0, None))[..., None, :]


def _wrap(deg: np.ndarray) -> np.ndarray:
    return (deg + 180.0) % 360.0 - 180.0


def _block_sd(model: ChainModel, lengths: np.ndarray, theta: np.ndarray, P_theta: np.ndarray) -> np.ndarray:
    """Returns (B, A) degrees: the model SD of every angle for B frames (theta (B, 33) rad, P_theta (B, 33, 33))."""
    B, n = P_theta.shape[0], P_theta.shape[-1]
    S = H * np.swapaxes(_square_roots(P_theta), -1, -2)  # (B, n, n): row i = h · column s_i
    sig = np.concatenate((theta[:, None, :] + S, theta[:, None, :] - S, theta[:, None, :]), axis=1)  # (B, 2n+1, 33)
    m = sig.shape[1]
    pos = model.positions(np.zeros((B, m, 3)), np.broadcast_to(lengths, (B, m, N_BONES)), sig)
    ang = joint_angles(pos)
    out = np.empty((B, len(ANGLE_NAMES)))
    for a, name in enumerate(ANGLE_NAMES):
        g = ang[name]
        plus, minus = _wrap(g[:, :n] - g[:, 2 * n : 2 * n + 1]), _wrap(g[:, n : 2 * n] - g[:, 2 * n : 2 * n + 1])
        first = (plus - minus) ** 2 / (4.0 * H**2)
        second = (H**2 - 1.0) / (4.0 * H**4) * (plus + minus) ** 2
        out[:, a] = np.sqrt(np.sum(first + second, axis=1))
    return out


def model_angle_sd(
    model: ChainModel,
    lengths: np.ndarray,
    theta: np.ndarray,
    P: np.ndarray,
    stride: int = DEFAULT_STRIDE,
) -> np.ndarray:
    """Returns (T, A) degrees: the SD of every angle of ANGLE_NAMES implied by the state covariance alone.

    model: the chain of the smoother. lengths: (19,) m. theta: (T, 33) rad. P: (T, 36, 36), covariance of
    (root m, theta rad) per frame; the root's rows do not matter (angles are differences of positions). NaN where
    an angle is undefined (e.g. shoulder rotation with a straight elbow reads NaN in some sigma points).
    """
    T = theta.shape[0]
    if theta.shape != (T, 33) or P.shape != (T, 36, 36) or lengths.shape != (N_BONES,):
        raise ValueError(
            f"expected theta (T, 33), P (T, 36, 36), lengths ({N_BONES},); got theta {theta.shape}, P {P.shape}, "
            f"lengths {lengths.shape}"
        )
    if stride < 1:
        raise ValueError(f"stride must be >= 1, got {stride}")
    if T == 0:
        return np.empty((0, len(ANGLE_NAMES)))
    picked = np.unique(np.r_[np.arange(0, T, stride), T - 1])
    sd = np.empty((len(picked), len(ANGLE_NAMES)))
    for s in range(0, len(picked), CHUNK_FRAMES):
        k = picked[s : s + CHUNK_FRAMES]
        sd[s : s + len(k)] = _block_sd(model, lengths, theta[k], P[k][:, 3:, 3:])
    if len(picked) == T:
        return sd
    frames = np.arange(T)
    return np.stack([np.interp(frames, picked, sd[:, a]) for a in range(sd.shape[1])], axis=1)


def angle_sd(
    model: ChainModel,
    lengths: np.ndarray,
    theta: np.ndarray,
    P: np.ndarray,
    stride: int = DEFAULT_STRIDE,
) -> dict[str, np.ndarray]:
    """Returns {angle: (T,) degrees}: the calibrated SD of each clinical angle's error per frame.

    INFLATION × model_angle_sd, floored at SD_FLOOR_DEG; arguments as model_angle_sd.
    """
    sd = np.maximum(INFLATION * model_angle_sd(model, lengths, theta, P, stride), SD_FLOOR_DEG)
    return {name: sd[:, a] for a, name in enumerate(ANGLE_NAMES)}


__all__ = ["INFLATION", "angle_sd", "model_angle_sd"]
