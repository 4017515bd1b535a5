"""Spatial registration: the least-squares rigid transform (Kabsch, no scale) between matching joint positions."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

TRIM = 0.10  # fraction of the worst residuals dropped before each refit


@dataclass(frozen=True)
class Registration:
    """dst ≈ R @ src + t. R: (3, 3) proper rotation; t: (3,) m; rms_m: RMS residual (m) of the kept pairs."""

    R: np.ndarray
    t: np.ndarray
    rms_m: float

    def apply(self, points: np.ndarray) -> np.ndarray:
        """Returns points (..., 3) m moved by the transform."""
        return points @ self.R.T + self.t

    def rotation_deg(self) -> float:
        """Returns the angle (degrees) of the rotation."""
        return rotation_deg(self.R)


def rotation_deg(R: np.ndarray) -> float:
    """Returns the angle (degrees) of the rotation R (3, 3)."""
    return float(np.degrees(np.arccos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0))))


def kabsch(src: np.ndarray, dst: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Returns (R (3, 3), t (3,)) minimising sum |R src + t - dst|^2 (a proper rotation). src, dst: (N, 3) m."""
    if src.shape != dst.shape or src.ndim != 2 or src.shape[1] != 3:
        raise ValueError(f"expected src and dst of one shape (N, 3); got {src.shape}, {dst.shape}")
    cs, cd = src.mean(axis=0), dst.mean(axis=0)
    H = (src - cs).T @ (dst - cd)
    U, _, Vt = np.linalg.svd(H)
    d = np.sign(np.linalg.det(Vt.T @ U.T))
    R = Vt.T @ np.diag([1.0, 1.0, d]) @ U.T
    return R, cd - R @ cs


def robust_kabsch(
    src: np.ndarray, dst: np.ndarray, trim: float = TRIM, iterations: int = 2
) -> tuple[np.ndarray, np.ndarray, float]:
    """Kabsch on (N, 3) point pairs (NaN rows ignored), refitted `iterations` times without the worst `trim` of the
    residuals. Returns R (3, 3), t (3,) m and the RMS residual (m) of the kept pairs."""
    ok = np.all(np.isfinite(src), axis=-1) & np.all(np.isfinite(dst), axis=-1)
    s, d = src[ok], dst[ok]
    if len(s) < 3:
        raise ValueError(f"registration needs at least 3 finite point pairs, got {len(s)}")
    keep = np.ones(len(s), bool)
    for _ in range(iterations + 1):
        R, t = kabsch(s[keep], d[keep])
        r = np.linalg.norm(s @ R.T + t - d, axis=-1)
        rms = float(np.sqrt(np.mean(r[keep] ** 2)))
        keep = r <= np.quantile(r, 1.0 - trim)
    return R, t, rms


def trimmed_rms(src: np.ndarray, dst: np.ndarray, trim: float = TRIM) -> float:
    """Returns the RMS distance (m) of (N, 3) point pairs without the worst `trim` of them (NaN rows ignored)."""
    r = np.linalg.norm(src - dst, axis=-1)
    r = r[np.isfinite(r)]
    if len(r) < 3:
        raise ValueError(f"registration needs at least 3 finite point pairs, got {len(r)}")
    return float(np.sqrt(np.mean(r[r <= np.quantile(r, 1.0 - trim)] ** 2)))


def register(
    src: np.ndarray, dst: np.ndarray, joints: np.ndarray, rigid: bool = True, trim: float = TRIM
) -> Registration:
    """Returns the trimmed rigid fit taking src onto dst over the joints (J,) bool; src, dst: (T, J, 3) m.

    rigid=False: the two are already in one frame (calibrated, as in the paper): the identity and its trimmed RMS.
    """
    s, d = src[:, joints].reshape(-1, 3), dst[:, joints].reshape(-1, 3)
    if not rigid:
        return Registration(np.eye(3), np.zeros(3), trimmed_rms(s, d, trim))
    R, t, rms = robust_kabsch(s, d, trim=trim)
    return Registration(R, t, rms)
