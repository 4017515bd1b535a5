"""Balance: sway of the body centre, projected on the floor, while the patient stands.

Definitions:
    body centre    = the midpoint of ROOT (hip centre) and SPINE, from smoothed positions (T, J, 3) m
                     (series.smooth_positions, Gaussian SD 0.1 s, which removes sensor jitter but not sway);
    floor plane    = the camera's x–z plane (y is up; a Kinect mounted level sees the floor horizontal);
    standing still = frames where both knees are flexed less than STANDING_KNEE_DEG (25°) and both hips less than
                     STANDING_HIP_DEG (30°) (clinical angles of kinect_agent.body.angles), and the body centre
                     and both ankles move slower than STILL_M_S (0.1 m/s): the legs stand still, the arms may
                     move (sway during an arm exercise counts; stepping, squatting and rising do not); only runs of
                     at least MIN_RUN_S (1 s) count, each measured on its own;
    sway_path_m    = Σ over standing runs of the horizontal distance the body centre travels, m;
    sway_area_m2   = area of the 95 % confidence ellipse of the horizontal body-centre positions, each run about
                     its own mean, pooled: π · χ²₂(0.95) · √(λ₁λ₂) with λ the covariance eigenvalues, m²;
    sway_velocity_m_s = sway_path_m / standing_s;  standing_s = total standing time, s.
None when the patient stood less than MIN_STANDING_S (2 s) in total.
"""

from __future__ import annotations

import numpy as np

from kinect_agent.analysis import series
from kinect_agent.skeleton import INDEX

STANDING_KNEE_DEG = 25.0
STANDING_HIP_DEG = 30.0
STILL_M_S = 0.1
MIN_RUN_S = 1.0
MIN_STANDING_S = 2.0
CHI2_95_2DOF = 5.991


def standing_frames(angles: dict[str, np.ndarray]) -> np.ndarray:
    """Returns (T,) bool: both knees and both hips near straight (NaN angles count as not standing)."""
    masks = [np.abs(angles[f"knee_flexion_{s}"]) < STANDING_KNEE_DEG for s in "LR"]
    masks += [np.abs(angles[f"hip_flexion_{s}"]) < STANDING_HIP_DEG for s in "LR"]
    return np.logical_and.reduce(masks)


def still_frames(t: np.ndarray, smoothed: np.ndarray) -> np.ndarray:
    """Returns (T,) bool: body centre and both ankles slower than STILL_M_S; smoothed: (T, J, 3) m, t: (T,) s."""
    if t.shape[0] < 2:
        return np.zeros(t.shape[0], dtype=bool)
    centre = 0.5 * (smoothed[:, INDEX["ROOT"]] + smoothed[:, INDEX["SPINE"]])
    parts = np.stack((centre, smoothed[:, INDEX["ANK_L"]], smoothed[:, INDEX["ANK_R"]]), axis=1)  # (T, 3, 3)
    speed = series.norm3(np.diff(parts, axis=0)) / np.diff(t)[:, None]
    slow = np.all(speed < STILL_M_S, axis=1)
    return np.concatenate((slow, slow[-1:]))


def _runs(mask: np.ndarray) -> np.ndarray:
    edges = np.flatnonzero(np.diff(np.concatenate(([0], mask.astype(np.int8), [0]))))
    return edges.reshape(-1, 2)


def sway(t: np.ndarray, smoothed: np.ndarray, angles: dict[str, np.ndarray]) -> dict[str, float] | None:
    """Returns {"sway_path_m", "sway_area_m2", "sway_velocity_m_s", "standing_s"} or None (see module doc).

    t: (T,) s; smoothed: (T, J, 3) m, camera frame, gap-filled and smoothed; angles: {name: (T,) degrees}.
    """
    centre = 0.5 * (smoothed[:, INDEX["ROOT"]] + smoothed[:, INDEX["SPINE"]])[:, [0, 2]]  # (T, 2) floor x, z
    stand = standing_frames(angles) & still_frames(t, smoothed) & np.all(np.isfinite(centre), axis=1)
    path, standing_s, pooled = 0.0, 0.0, []
    for a, b in _runs(stand):
        if b - a < 2 or t[b - 1] - t[a] < MIN_RUN_S:
            continue
        c = centre[a:b]
        path += float(np.sum(np.linalg.norm(np.diff(c, axis=0), axis=1)))
        standing_s += float(t[b - 1] - t[a])
        pooled.append(c - c.mean(axis=0))
    if standing_s < MIN_STANDING_S:
        return None
    eig = np.clip(np.linalg.eigvalsh(np.cov(np.concatenate(pooled).T)), 0.0, None)
    area = float(np.pi * CHI2_95_2DOF * np.sqrt(eig[0] * eig[1]))
    return {
        "sway_path_m": round(path, 4),
        "sway_area_m2": round(area, 6),
        "sway_velocity_m_s": round(path / standing_s, 4),
        "standing_s": round(standing_s, 2),
    }
