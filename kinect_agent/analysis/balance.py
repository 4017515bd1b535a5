"""Balance: sway of the centre of mass of the trunk and hips, projected on the floor, while the patient stands.

Method (a Kinect estimate of centre-of-pressure posturography, after Clark et al. 2010, Gait & Posture 31:307,
who validated Kinect trunk/pelvis sway against a force plate in quiet standing):
    centre of mass  = the mean of ROOT, SPINE, HIP_L and HIP_R: the pelvis and lower trunk, which carry about
                      60 % of the body mass and move with the whole body when it sways at the ankles; the arms,
                      head and legs are left out because an arm exercise moves them on purpose;
                      positions (T, J, 3) m, camera frame, smoothed again with a Gaussian of SD SWAY_SMOOTH_S
                      (0.3 s, removing most sensor jitter; why: bench/README.md, "Balance");
    floor plane     = the camera's x–z plane (y is up; a Kinect mounted level sees the floor horizontal);
    standing phase  = frames where the pelvis is at least STANDING_HEIGHT_FRAC (0.85) of the legs' length above
                      the lower ankle (neither seated nor squatting; no knee angle is used, Kinect's knee angles
                      being biased by 10-25° in quiet standing), both hips flexed less than STANDING_HIP_DEG (30°)
                      (not bent forward, no leg raised in front), both ankles within FOOT_LIFT_M (5 cm) of the same
                      height (no foot lifted), both ankles (smoothed with SD FEET_SMOOTH_S, 0.5 s) slower than
                      FEET_STILL_M_S (0.1 m/s) and the centre of mass slower than STILL_M_S (0.1 m/s) (no step, no
                      shift of weight); a run ends where two frames lie more than MAX_STEP_S (1 s) apart (the
                      patient out of the picture, a hidden page, a slow camera page: time without frames is not
                      time seen standing); only runs of at least MIN_RUN_S (1 s) count, each measured on its own;
    sway_path_m     = Σ over standing runs of the horizontal distance the centre of mass travels, m;
    sway_area_m2    = area of the 95 % confidence ellipse of the horizontal positions, each run about its own
                      mean, pooled: π · χ²₂(0.95) · √(λ₁λ₂) with λ the covariance eigenvalues, m²;
    sway_velocity_m_s = sway_path_m / standing_s; standing_s = total standing time, s;
    sway_velocity_95  = [low, high] m/s: 95 % percentile interval of sway_velocity_m_s over BOOTSTRAP (1000)
                      resamples (fixed seed) of the standing time cut into WINDOW_S (2 s) windows (at most one per
                      frame step: a run seen at a few frames a second has no empty window), weighted by their length
                      (the window-to-window variability of the patient's sway and of the sensor; it
                      does not contain the sensor's bias, see Limits);
    n_windows       = number of windows the interval rests on.
None when the patient stood less than MIN_STANDING_S (2 s) in total; missing_reason() says why in words.

Limits: the trunk-and-hips point is not the whole-body centre of mass (a lean of the head and arms is not seen) and
the camera measures no centre of pressure; the sensor's residual jitter after the agent's filter adds about
1.2-1.6 cm/s (bench/README.md, "Balance"), so the value compares sessions of one patient on one camera rather than
force-plate norms, and differences under about 1 cm/s are not meaningful; a camera that is not level tilts the floor
plane (cos of the tilt on one axis).
"""

from __future__ import annotations

import numpy as np

from kinect_agent.analysis import reasons as why
from kinect_agent.analysis import series
from kinect_agent.analysis.reasons import Reason
from kinect_agent.skeleton import INDEX

STANDING_HEIGHT_FRAC = 0.85
STANDING_HIP_DEG = 30.0
FOOT_LIFT_M = 0.05
FEET_STILL_M_S = 0.1
FEET_SMOOTH_S = 0.5
STILL_M_S = 0.1
SWAY_SMOOTH_S = 0.3
MIN_RUN_S = 1.0
MAX_STEP_S = 1.0
MIN_STANDING_S = 2.0
WINDOW_S = 2.0
BOOTSTRAP = 1000
CHI2_95_2DOF = 5.991
COM_JOINTS = ("ROOT", "SPINE", "HIP_L", "HIP_R")
_COM = [INDEX[j] for j in COM_JOINTS]
_ANK = [INDEX["ANK_L"], INDEX["ANK_R"]]


def centre_of_mass(positions: np.ndarray) -> np.ndarray:
    """Returns (T, 3) m, camera frame: the mean of the trunk and hip joints (COM_JOINTS) of positions (T, J, 3) m."""
    return positions[:, _COM].mean(axis=1)


def _leg_length(positions: np.ndarray) -> float:
    """Returns the median hip-knee-ankle length of both legs over frames, m; positions (T, J, 3) m."""
    legs = []
    for s in "LR":
        h, k, a = (positions[:, INDEX[f"{j}_{s}"]] for j in ("HIP", "KNE", "ANK"))
        legs.append(np.linalg.norm(k - h, axis=1) + np.linalg.norm(a - k, axis=1))
    return float(np.nanmedian(np.concatenate(legs)))


def _speed(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Returns (T, ...) m/s: the speed of x (T, ..., 3) m, the last difference repeated."""
    v = series.norm3(np.diff(x, axis=0)) / np.diff(t).reshape((-1,) + (1,) * (x.ndim - 2))
    return np.concatenate((v, v[-1:]))


def standing_frames(t: np.ndarray, smoothed: np.ndarray, angles: dict[str, np.ndarray]) -> np.ndarray:
    """Returns (T,) bool: the standing phase of the module doc; smoothed (T, J, 3) m; angles {name: (T,) deg}."""
    T = t.shape[0]
    if T < 2:
        return np.zeros(T, dtype=bool)
    p = series.smooth_positions(t, smoothed, smooth_s=SWAY_SMOOTH_S)
    ankles = p[:, _ANK]  # (T, 2, 3)
    slow_ankles = series.smooth_positions(t, smoothed[:, _ANK], smooth_s=FEET_SMOOTH_S)
    floor_y = np.min(ankles[:, :, 1], axis=1)
    pelvis_up = p[:, INDEX["ROOT"], 1] - floor_y >= STANDING_HEIGHT_FRAC * _leg_length(p)
    hips = np.logical_and.reduce([np.abs(angles[f"hip_flexion_{s}"]) < STANDING_HIP_DEG for s in "LR"])
    feet_down = np.abs(ankles[:, 0, 1] - ankles[:, 1, 1]) < FOOT_LIFT_M
    feet_still = np.all(_speed(t, slow_ankles) < FEET_STILL_M_S, axis=1)
    com_still = _speed(t, centre_of_mass(p)) < STILL_M_S
    with np.errstate(invalid="ignore"):
        return pelvis_up & hips & feet_down & feet_still & com_still


def _runs(t: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Returns (R, 2) [start, end) frame indices of the runs of mask (T,) bool, cut where frames of t (T,) s lie more
    than MAX_STEP_S apart."""
    cut = np.concatenate((np.diff(t) > MAX_STEP_S, [False]))  # (T,) True on a run's last frame before a gap
    edges = np.flatnonzero(np.diff(np.concatenate(([0], mask.astype(np.int8), [0]))))
    runs = edges.reshape(-1, 2)
    out: list[tuple[int, int]] = []
    for a, b in runs:
        ends = np.flatnonzero(cut[a : b - 1]) + a + 1  # (k,) first frames after a gap inside the run
        bounds = np.concatenate(([a], ends, [b]))
        out.extend((int(lo), int(hi)) for lo, hi in zip(bounds[:-1], bounds[1:], strict=True))
    return np.asarray(out, dtype=np.int64).reshape(-1, 2)


def _interval(windows: list[tuple[float, float]]) -> list[float]:
    """Returns [low, high] m/s, the bootstrap 95 % interval of Σpath/Σtime over (path m, time s) windows."""
    w = np.asarray(windows)
    idx = np.random.default_rng(0).integers(0, len(w), size=(BOOTSTRAP, len(w)))
    v = w[idx, 0].sum(axis=1) / w[idx, 1].sum(axis=1)
    lo, hi = np.percentile(v, [2.5, 97.5])
    return [round(float(lo), 4), round(float(hi), 4)]


def sway(t: np.ndarray, smoothed: np.ndarray, angles: dict[str, np.ndarray]) -> dict[str, object] | None:
    """Returns {"sway_path_m", "sway_area_m2", "sway_velocity_m_s", "sway_velocity_95", "standing_s", "n_windows",
    "method"} or None (see module doc).

    t: (T,) s; smoothed: (T, J, 3) m, camera frame, gap-filled and smoothed; angles: {name: (T,) degrees}.
    """
    p = series.smooth_positions(t, smoothed, smooth_s=SWAY_SMOOTH_S)
    centre = centre_of_mass(p)[:, [0, 2]]  # (T, 2) floor x, z
    stand = standing_frames(t, smoothed, angles) & np.all(np.isfinite(centre), axis=1)
    path, standing_s, pooled, windows = 0.0, 0.0, [], []
    for a, b in _runs(t, stand):
        if b - a < 2 or t[b - 1] - t[a] < MIN_RUN_S:
            continue
        c = centre[a:b]
        step = np.linalg.norm(np.diff(c, axis=0), axis=1)  # (n-1,) m
        dt = np.diff(t[a:b])
        path += float(step.sum())
        standing_s += float(dt.sum())
        pooled.append(c - c.mean(axis=0))
        n_win = min(step.size, max(1, int(round(dt.sum() / WINDOW_S))))
        for part_step, part_dt in zip(np.array_split(step, n_win), np.array_split(dt, n_win), strict=True):
            windows.append((float(part_step.sum()), float(part_dt.sum())))
    if standing_s < MIN_STANDING_S:
        return None
    eig = np.clip(np.linalg.eigvalsh(np.cov(np.concatenate(pooled).T)), 0.0, None)
    area = float(np.pi * CHI2_95_2DOF * np.sqrt(eig[0] * eig[1]))
    return {
        "sway_path_m": round(path, 4),
        "sway_area_m2": round(area, 6),
        "sway_velocity_m_s": round(path / standing_s, 4),
        "sway_velocity_95": _interval(windows),
        "standing_s": round(standing_s, 2),
        "n_windows": len(windows),
        "method": "trunk-and-hips centre of mass, standing phases",
    }


def missing_reason(t: np.ndarray, smoothed: np.ndarray, angles: dict[str, np.ndarray]) -> Reason:
    """Returns why sway() is None (a Reason of kinect_agent.analysis.reasons) for this recording (the first
    condition that failed)."""
    T = t.shape[0]
    if T < 2:
        return why.RECORDING_TOO_SHORT.reason()
    p = series.smooth_positions(t, smoothed, smooth_s=SWAY_SMOOTH_S)
    floor_y = np.min(p[:, _ANK, 1], axis=1)
    with np.errstate(invalid="ignore"):
        up = p[:, INDEX["ROOT"], 1] - floor_y >= STANDING_HEIGHT_FRAC * _leg_length(p)
    dur = float(t[-1] - t[0])
    if float(np.mean(up)) * dur < MIN_STANDING_S:
        return why.NOT_STANDING.reason()
    return why.NEVER_STILL.reason(seconds=MIN_STANDING_S)
