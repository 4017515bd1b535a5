"""The webcam's offline filter: each joint coordinate smoothed on its own, with no body model, restarted at label swaps.

Why not the kinematic chain: a monocular landmarker's depth is poor and its bone lengths come from the model's
prior, and from the side it swaps left and right. The chain UKF imposes one length per bone and a continuous
labelling; on Pose2Sim's four views it made 26 of 56 angle x view cells worse than the landmarker's own output, by
up to 34 degrees, mostly where it smoothed across swaps (bench/README.md, "Webcam angles: why the pipeline made them
worse"). This filter assumes only what the data show: each coordinate moves smoothly (constant velocity between
frames, perturbed by white acceleration), is measured with the webcam's measured jitter, and the labelling is
continuous only between two flips (label_swaps.labelling_flips) and the body is the same one only between two jumps
of the hips faster than a body moves (label_swaps.body_jumps: another person taken for the patient).

Per coordinate c of joint j, state (position m, velocity m/s), the discrete white-noise-acceleration model
(Bar-Shalom, Li & Kirubarajan 2001, §6.3.2):

    x_k = F x_{k-1} + w,  F = [[1, dt], [0, 1]],  Q = q² [[dt⁴/4, dt³/2], [dt³/2, dt²]],  q = joint_accel_sd_mps2
    z_k = x_k[0] + v,     R = joint_sigma_image_m² (x, y) or joint_sigma_depth_m² (z), times INFERRED_FACTOR² for
                          an inferred joint; an untracked sample is no measurement (the filter predicts through it)

run forward (Kalman filter) and backward (Rauch-Tung-Striebel) within each run of frames between two restarts,
vectorised over the 60 coordinates. A run shorter than MIN_RUN frames is left as measured. Output: every joint of
every frame (a joint never measured within a run is filled linearly in time from its neighbours, ik.fill_gaps).
"""

from __future__ import annotations

import numpy as np

from kinect_agent import skeleton
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.processing.ik import fill_gaps
from kinect_agent.processing.label_swaps import body_jumps, labelling_flips
from kinect_agent.recording import Recording

INFERRED_FACTOR = 2.0  # an inferred joint's measurement SD relative to a tracked one's (as sigma_inferred_m)
MIN_RUN = 3  # frames: a shorter run between two flips is left as measured
ROOT_SPEED_LIMIT_M_S = 2.0  # the trunk's speed limit of excursions.py: a faster hip is another body
JUMP_NOISE_SD = 4.0  # a body jump must exceed the speed limit by this many SDs of a frame-to-frame difference
VELOCITY_SD0_M_S = 2.0  # initial SD of each coordinate's velocity, m/s (a limb's speed in an exercise)


def constant_velocity_rts(z: np.ndarray, r_sd: np.ndarray, accel_sd: float, dt: float) -> np.ndarray:
    """Returns (T, S) the RTS-smoothed positions of S independent constant-velocity series (module docstring).

    z: (T, S) measurements (any unit, m here), NaN = missing; r_sd: (T, S) or (S,) measurement SD, same unit;
    accel_sd: white acceleration SD (unit/s²); dt: frame interval, s. A series never measured stays NaN.
    """
    if z.ndim != 2:
        raise ValueError(f"z must have shape (T, S), got {z.shape}")
    T, S = z.shape
    r2 = np.broadcast_to(np.asarray(r_sd, dtype=np.float64) ** 2, (T, S))
    F = np.array([[1.0, dt], [0.0, 1.0]])
    Q = accel_sd**2 * np.array([[dt**4 / 4, dt**3 / 2], [dt**3 / 2, dt**2]])
    seen = np.isfinite(z)
    first = np.where(seen.any(axis=0), np.argmax(seen, axis=0), 0)
    x = np.zeros((S, 2))
    x[:, 0] = np.where(seen.any(axis=0), z[first, np.arange(S)], 0.0)
    P = np.zeros((S, 2, 2))
    P[:, 0, 0], P[:, 1, 1] = r2[first, np.arange(S)], VELOCITY_SD0_M_S**2
    xf, Pf = np.empty((T, S, 2)), np.empty((T, S, 2, 2))
    xp, Pp = np.empty((T, S, 2)), np.empty((T, S, 2, 2))
    for k in range(T):
        if k:
            x = x @ F.T
            P = F @ P @ F.T + Q
        xp[k], Pp[k] = x, P
        gain = np.where(seen[k][:, None], P[:, :, 0] / (P[:, 0, 0] + r2[k])[:, None], 0.0)  # (S, 2)
        x = x + gain * np.where(seen[k], z[k] - x[:, 0], 0.0)[:, None]
        P = P - gain[:, :, None] * P[:, None, 0, :]
        xf[k], Pf[k] = x, P
    xs = xf.copy()
    for k in range(T - 2, -1, -1):
        G = Pf[k] @ F.T @ np.linalg.inv(Pp[k + 1])  # (S, 2, 2)
        xs[k] = xf[k] + np.einsum("sij,sj->si", G, xs[k + 1] - xp[k + 1])
    out = xs[..., 0]
    out[:, ~seen.any(axis=0)] = np.nan
    return out


def smooth_joints(rec: Recording, config: PipelineConfig) -> tuple[np.ndarray, np.ndarray]:
    """Returns (positions (T, J, 3) m, camera frame, every joint filled; restarts (T,) bool, the label swaps and body
    jumps it restarted at) of a recording filtered by the joint smoother with config's joint_* settings (module
    docstring)."""
    T = rec.n_frames
    z = np.where((rec.state != skeleton.NOT_TRACKED)[..., None], rec.positions, np.nan)
    axis_sd = np.array([config.joint_sigma_image_m, config.joint_sigma_image_m, config.joint_sigma_depth_m])
    factor = np.where(rec.state == skeleton.INFERRED, INFERRED_FACTOR, 1.0)  # (T, J)
    r_sd = (factor[..., None] * axis_sd).reshape(T, -1)
    steps = np.diff(rec.t)
    dt = float(np.median(steps[steps > 0])) if np.any(steps > 0) else 1.0 / config.rate_ref_hz
    flips = np.zeros(T, dtype=bool)
    if config.joint_split_at_swaps:
        noise = JUMP_NOISE_SD * np.sqrt(2.0) * config.joint_sigma_image_m
        flips = labelling_flips(z) | body_jumps(z, rec.t, ROOT_SPEED_LIMIT_M_S, noise)
    bounds = [0, *np.flatnonzero(flips).tolist(), T]
    flat = z.reshape(T, -1)
    out = flat.copy()
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        if b - a >= MIN_RUN:
            out[a:b] = constant_velocity_rts(flat[a:b], r_sd[a:b], config.joint_accel_sd_mps2, dt)
    return fill_gaps(out.reshape(T, skeleton.J, 3)), flips


__all__ = ["INFERRED_FACTOR", "MIN_RUN", "constant_velocity_rts", "smooth_joints"]
