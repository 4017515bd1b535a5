"""The webcam's offline filter: each joint coordinate smoothed on its own, with no body model, restarted at label swaps.

Why not the kinematic chain: a monocular landmarker's depth is poor and its bone lengths come from the model's
prior, and from the side it swaps left and right. The chain UKF imposes one length per bone and a continuous
labelling; on Pose2Sim's four views it made 26 of 56 angle x view cells worse than the landmarker's own output, by
up to 34 degrees, mostly where it smoothed across swaps (bench/README.md, "Webcam angles: why the pipeline made them
worse"). This filter assumes only what the data show: each coordinate moves smoothly (constant velocity between
frames, perturbed by white acceleration), is measured with the webcam's measured jitter, and the labelling is
continuous only between two flips (label_swaps.labelling_flips: the whole body; with joint_arm_swaps also
label_swaps.pair_swaps: the arms alone) and the body is the same one only between two jumps of the hips faster than
a body moves (label_swaps.body_jumps: another person taken for the patient).

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
from kinect_agent.processing.label_swaps import body_jumps, labelling_flips, pair_swaps
from kinect_agent.recording import Recording

INFERRED_FACTOR = 2.0  # an inferred joint's measurement SD relative to a tracked one's (as sigma_inferred_m)
MIN_RUN = 3  # frames: a shorter run between two flips is left as measured
ROOT_SPEED_LIMIT_M_S = 2.0  # the trunk's speed limit of excursions.py: a faster hip is another body
JUMP_NOISE_SD = 4.0  # a body jump must exceed the speed limit by this many SDs of a frame-to-frame difference
VELOCITY_SD0_M_S = 2.0  # initial SD of each coordinate's velocity, m/s (a limb's speed in an exercise)


class ConstantVelocityFilter:
    """S independent constant-velocity Kalman filters, one per series (module docstring), filterpy style.

    x: (S, 2) position and velocity of each series (NaN before its first measurement); P: (S, 2, 2) their
    covariances. A series starts at its first measurement (x = (z, 0), P = diag(r², VELOCITY_SD0_M_S²)), which is
    then also its first update.
    """

    def __init__(self, n_series: int, accel_sd: float) -> None:
        self.accel_sd = accel_sd
        self.x = np.full((n_series, 2), np.nan)
        self.P = np.zeros((n_series, 2, 2))
        self.started = np.zeros(n_series, dtype=bool)

    def transition(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """Returns (F (2, 2), Q (2, 2)) of a step of dt seconds."""
        F = np.array([[1.0, dt], [0.0, 1.0]])
        Q = self.accel_sd**2 * np.array([[dt**4 / 4, dt**3 / 2], [dt**3 / 2, dt**2]])
        return F, Q

    def predict(self, dt: float) -> None:
        """Moves x and P of the started series dt seconds on."""
        F, Q = self.transition(dt)
        self.x = self.x @ F.T
        self.P = np.where(self.started[:, None, None], F @ self.P @ F.T + Q, self.P)

    def update(self, z: np.ndarray, r_sd: np.ndarray) -> None:
        """Updates x and P with measurements z: (S,) NaN = missing, SD r_sd: (S,) (a series' first one starts it)."""
        seen = np.isfinite(z)
        r2 = np.broadcast_to(np.asarray(r_sd, dtype=np.float64) ** 2, z.shape)
        new = seen & ~self.started
        self.x[new] = np.stack([z[new], np.zeros(int(new.sum()))], axis=1)
        self.P[new] = 0.0
        self.P[new, 0, 0], self.P[new, 1, 1] = r2[new], VELOCITY_SD0_M_S**2
        self.started |= seen
        P = self.P
        gain = np.where(seen[:, None], P[:, :, 0] / (P[:, 0, 0] + r2)[:, None], 0.0)  # (S, 2)
        self.x = self.x + gain * np.where(seen, z - self.x[:, 0], 0.0)[:, None]
        self.P = P - gain[:, :, None] * P[:, None, 0, :]

    def restart(self) -> None:
        """Forgets every series: each starts again at its next measurement."""
        self.x[:] = np.nan
        self.P[:] = 0.0
        self.started[:] = False


def constant_velocity_rts(z: np.ndarray, r_sd: np.ndarray, accel_sd: float, t: np.ndarray) -> np.ndarray:
    """Returns (T, S) the RTS-smoothed positions of S independent constant-velocity series (module docstring): the
    forward pass is ConstantVelocityFilter, the causal filter of the live count (JointFilter), frame by frame.

    z: (T, S) measurements (any unit, m here), NaN = missing; r_sd: (T, S) or (S,) measurement SD, same unit;
    accel_sd: white acceleration SD (unit/s²); t: (T,) frame times, s. A series is NaN before its first measurement.
    """
    if z.ndim != 2:
        raise ValueError(f"z must have shape (T, S), got {z.shape}")
    T, S = z.shape
    if np.shape(t) != (T,):
        raise ValueError(f"t must have shape ({T},), got {np.shape(t)}")
    r = np.broadcast_to(np.asarray(r_sd, dtype=np.float64), (T, S))
    kf = ConstantVelocityFilter(S, accel_sd)
    xf, Pf = np.empty((T, S, 2)), np.empty((T, S, 2, 2))
    xp, Pp = np.empty((T, S, 2)), np.empty((T, S, 2, 2))
    for k in range(T):
        if k:
            kf.predict(float(t[k] - t[k - 1]))
        xp[k], Pp[k] = kf.x, kf.P
        kf.update(z[k], r[k])
        xf[k], Pf[k] = kf.x, kf.P
    xs = xf.copy()
    for k in range(T - 2, -1, -1):
        F, _ = kf.transition(float(t[k + 1] - t[k]))
        go = np.isfinite(xf[k, :, 0])  # started at k (so at k + 1 too)
        Ppn = np.where(go[:, None, None], Pp[k + 1], np.eye(2))
        G = Pf[k] @ F.T @ np.linalg.inv(Ppn)  # (S, 2, 2)
        step = np.einsum("sij,sj->si", G, np.where(go[:, None], xs[k + 1] - xp[k + 1], 0.0))
        xs[k] = np.where(go[:, None], xf[k] + step, np.nan)
    return xs[..., 0]


def _measurements(positions: np.ndarray, state: np.ndarray, config: PipelineConfig) -> tuple[np.ndarray, np.ndarray]:
    """Returns (z (..., J, 3) m, NaN = untracked; r_sd (..., J * 3) m) of frames: positions (..., J, 3), state
    (..., J)."""
    z = np.where((state != skeleton.NOT_TRACKED)[..., None], positions, np.nan)
    axis_sd = np.array([config.joint_sigma_image_m, config.joint_sigma_image_m, config.joint_sigma_depth_m])
    factor = np.where(state == skeleton.INFERRED, INFERRED_FACTOR, 1.0)
    r_sd = (factor[..., None] * axis_sd).reshape(*state.shape[:-1], -1)
    return z, r_sd


def restarts_between(z_prev: np.ndarray, z: np.ndarray, t_prev: float, t: float, config: PipelineConfig) -> bool:
    """Returns whether the joints filter restarts at a frame z: (J, 3) m after z_prev: (J, 3) (a label swap of the
    whole body or, with joint_arm_swaps, of the arms alone, or a body jump between them; label_swaps), the rule both
    passes apply."""
    if not config.joint_split_at_swaps:
        return False
    pair, times = np.stack([z_prev, z]), np.array([t_prev, t])
    if labelling_flips(pair)[1] or (config.joint_arm_swaps and pair_swaps(pair)[1]):
        return True
    noise = JUMP_NOISE_SD * np.sqrt(2.0) * config.joint_sigma_image_m
    return bool(body_jumps(pair, times, ROOT_SPEED_LIMIT_M_S, noise)[1])


class JointFilter:
    """The joints filter's forward pass, causal, frame by frame: the webcam's live filter (what the live count and
    the stored count of a webcam set are counted on, kinect_agent.analysis.live.counting_positions).

    Restarts where the offline smoother does (restarts_between); step() returns each frame's filtered joints, NaN
    where a coordinate was not measured since the last restart.
    """

    def __init__(self, config: PipelineConfig) -> None:
        self.config = config
        self.kf = ConstantVelocityFilter(skeleton.J * 3, config.joint_accel_sd_mps2)
        self.z_last: np.ndarray | None = None
        self.t_last = float("nan")
        self.n_restarts = 0

    def step(self, t: float, positions: np.ndarray, tracking: np.ndarray) -> np.ndarray:
        """Returns (J, 3) m the filtered joints of one frame: positions (J, 3) m camera frame, tracking (J,) 0/1/2."""
        if positions.shape != (skeleton.J, 3) or tracking.shape != (skeleton.J,):
            raise ValueError(f"a frame must be ({skeleton.J}, 3) and ({skeleton.J},), got {positions.shape}, "
                             f"{tracking.shape}")  # fmt: skip
        z, r_sd = _measurements(positions, tracking, self.config)
        if self.z_last is not None:
            if restarts_between(self.z_last, z, self.t_last, t, self.config):
                self.kf.restart()
                self.n_restarts += 1
            else:
                self.kf.predict(t - self.t_last)
        self.kf.update(z.reshape(-1), r_sd)
        self.z_last, self.t_last = z, t
        return self.kf.x[:, 0].reshape(skeleton.J, 3).copy()


def forward_joints(rec: Recording, config: PipelineConfig) -> np.ndarray:
    """Returns (T, J, 3) m, camera frame, NaN where not measured since a restart: JointFilter over the recording."""
    f = JointFilter(config)
    return np.stack([f.step(float(rec.t[k]), rec.positions[k], rec.state[k]) for k in range(rec.n_frames)])


def smooth_joints(rec: Recording, config: PipelineConfig) -> tuple[np.ndarray, np.ndarray]:
    """Returns (positions (T, J, 3) m, camera frame, every joint filled; restarts (T,) bool, the label swaps and body
    jumps it restarted at) of a recording filtered by the joint smoother with config's joint_* settings (module
    docstring)."""
    T = rec.n_frames
    z, r_sd = _measurements(rec.positions, rec.state, config)
    flips = np.zeros(T, dtype=bool)
    for k in range(1, T):
        flips[k] = restarts_between(z[k - 1], z[k], float(rec.t[k - 1]), float(rec.t[k]), config)
    bounds = [0, *np.flatnonzero(flips).tolist(), T]
    flat = z.reshape(T, -1)
    out = flat.copy()
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        if b - a >= MIN_RUN:
            out[a:b] = constant_velocity_rts(flat[a:b], r_sd[a:b], config.joint_accel_sd_mps2, rec.t[a:b])
    return fill_gaps(out.reshape(T, skeleton.J, 3)), flips


__all__ = [
    "INFERRED_FACTOR",
    "MIN_RUN",
    "ConstantVelocityFilter",
    "JointFilter",
    "constant_velocity_rts",
    "forward_joints",
    "restarts_between",
    "smooth_joints",
]
