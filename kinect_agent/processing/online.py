"""The online filter: the forward pass of the kinematic UKF frame by frame, for live feedback.

OnlineFilter.step takes one frame and returns its filtered joints; run_online runs it over a whole recording
(pipeline.process(online=True)) and returns the parameter estimates per frame.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from kinect_agent import skeleton
from kinect_agent.body import kinematics as km
from kinect_agent.body.rotations import matrix_to_rotvec
from kinect_agent.processing import length_bias
from kinect_agent.processing.chain_filter import N_LEN, N_ROOT, N_TH, ChainFilter
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.processing.errors import ProcessingError
from kinect_agent.processing.excursions import LiveExcursions
from kinect_agent.processing.ik import inverse_kinematics
from kinect_agent.processing.joint_smoother import JointFilter
from kinect_agent.recording import Recording
from kinect_agent.skeleton import INFERRED, NOT_TRACKED

Progress = Callable[[int, int], None]
TRUNK = tuple(skeleton.INDEX[n] for n in ("ROOT", "SPINE", "HIP_L", "HIP_R"))  # joints that must be seen to start


def _ik_state(model: km.ChainModel, positions: np.ndarray) -> np.ndarray:
    """Returns (36,) root (m) + theta (rad) of one frame by inverse kinematics, against `model`'s references.

    positions: (J, 3) m, camera frame, NaN = untracked.
    """
    ik = inverse_kinematics(positions[None])
    theta = ik.theta[0].copy()
    R = ik.model.local_rotations(theta)[km.ROT_3DOF]  # (7, 3, 3) local rotations of the 3-DoF joints
    theta[km.THETA_3DOF] = matrix_to_rotvec(np.swapaxes(model.R_ref, -1, -2) @ R).reshape(-1)
    return np.concatenate((ik.root[0], theta))


class OnlineFilter:
    """The forward pass frame by frame, for live feedback (one UKF step per frame, p99 ≲ 2 ms).

    Tracked joints enter with SD config.online_sigma_tracked_m (0.07 m per axis, as offline's default) and, by
    default, no innovation gate (config.online_gate_chi2): both measured best on the tuning set under 2-6 %
    tracking loss (bench/README.md). Joints in a sustained excursion (excursions.LiveExcursions, causal;
    config.online_excursions) are treated as missing. With a gate, a joint gated for config.online_reacquire_s
    without a break is restarted from inverse kinematics of the frame (_ik_state).
    Segment lengths: given (19,) m, or part of the state during the first config.online_init_s seconds and fixed
    after.
    The first frame with at least the trunk observed starts the filter (IK of that frame); before that, step()
    returns the input with gaps filled by the previous output (NaN where nothing is known yet).
    kf: the chain's UKF once started (None before); its model's references are re-centred as angles grow.
    """

    def __init__(self, config: PipelineConfig | None = None, lengths: np.ndarray | None = None) -> None:
        self.config = config or PipelineConfig()
        if lengths is not None:
            lengths = np.asarray(lengths, dtype=np.float64)
            if lengths.shape != (N_LEN,):
                raise ValueError(f"lengths must have shape ({N_LEN},), got {lengths.shape}")
            if not np.all(np.isfinite(lengths) & (lengths > 0)):
                raise ValueError("lengths must be finite and > 0 metres")
        self.given_lengths = lengths
        self.kf: ChainFilter | None = None
        self.t0 = math.nan  # s, the frame that started the filter (NaN before)
        self.t_last = math.nan  # s, the last frame stepped (NaN before)
        self.last = np.full((skeleton.J, 3), np.nan)
        self.n_gated = 0
        self.gated_since = np.full(skeleton.J, np.nan)  # s, start of each joint's current run of gated frames
        c = self.config
        self.excursions = (
            LiveExcursions(c.excursion_min_dev_m, c.excursion_min_len_s, c.excursion_max_len_s)
            if c.online_excursions else None
        )  # fmt: skip
        self.n_held = 0

    @property
    def lengths_fixed(self) -> bool:
        """True once the segment lengths are constants of the filter."""
        return self.kf is not None and self.kf.lengths is not None

    def _start(self, t: float, positions: np.ndarray) -> ChainFilter:
        # One frame starts the filter: a joint whose bone to its parent is implausible (an outlier in this very
        # frame) is left out, so that IK places it at a typical offset instead of anchoring the state on it.
        reference = self.given_lengths if self.given_lengths is not None else km.TYPICAL_LENGTHS
        bone = skeleton.bone_lengths(positions)
        odd = ~((bone > 0.5 * reference) & (bone < 2.0 * reference)) & np.isfinite(bone)
        positions = positions.copy()
        positions[1:][odd] = np.nan
        ik = inverse_kinematics(positions[None])
        lengths = self.given_lengths
        parts = [ik.root[0]] + ([] if lengths is not None else [ik.lengths]) + [ik.theta[0]]
        self.kf = ChainFilter(ik.model, lengths, self.config, np.concatenate(parts))
        self.t0, self.t_last = t, t
        return self.kf

    def fix_lengths(self) -> None:
        """Ends the estimation of the segment lengths: from now on they are the state's current ones (19,) m.
        Nothing to do before the filter has started."""
        kf = self.kf
        if kf is not None and kf.lengths is None:
            lengths = length_bias.apply(kf.x[N_ROOT : N_ROOT + N_LEN], self.config.length_bias)
            self.kf = kf.with_lengths_fixed(lengths, self.config)

    def step(self, t: float, positions: np.ndarray, state: np.ndarray) -> np.ndarray:
        """Returns the filtered joint positions (J, 3) m for one frame.

        t: s, increasing. positions: (J, 3) m camera frame, NaN = untracked. state: (J,) 0/1/2.
        """
        positions = np.asarray(positions, dtype=np.float64)
        state = np.asarray(state)
        if positions.shape != (skeleton.J, 3):
            raise ValueError(f"positions must have shape ({skeleton.J}, 3), got {positions.shape}")
        if state.shape != (skeleton.J,):
            raise ValueError(f"state must have shape ({skeleton.J},), got {state.shape}")
        if not np.isfinite(t):
            raise ValueError(f"t must be finite, got {t!r}")
        if t <= self.t_last:  # False while t_last is NaN
            raise ValueError(f"t must increase: got {t} after {self.t_last}")
        present = (state != NOT_TRACKED) & np.all(np.isfinite(positions), axis=1)
        if self.excursions is not None:
            held = self.excursions.step(t, positions, present)
            self.n_held += int(held.sum())
            present &= ~held
        if self.kf is None:
            if not present[list(TRUNK)].all():
                out = np.where(present[:, None], positions, self.last)
                self.last = out
                return out.copy()
            kf = self._start(t, np.where(present[:, None], positions, np.nan))
        else:
            if not self.lengths_fixed and t - self.t0 >= self.config.online_init_s:
                self.fix_lengths()
            kf = self.kf
            kf.predict_random_walk(max(t - self.t_last, 1e-6) * self.config.rate_ref_hz)
        self.t_last = t
        self._update(kf, t, positions, state, present)
        kf.model.fold_references(kf.theta())
        out = kf.positions()
        self.last = out
        return out

    def _update(self, kf: ChainFilter, t: float, positions: np.ndarray, state: np.ndarray, present: np.ndarray) -> None:
        """Restarts joints that lost track, then the gated update with the present joints."""
        if not present.any():
            return
        z = positions.reshape(-1)
        observed = np.repeat(present, 3)
        sd = np.where(state == INFERRED, self.config.sigma_inferred_m, self.config.online_sigma_tracked_m)
        R_diag = np.repeat(sd**2, 3)
        lost = present & (t - self.gated_since >= (self.config.online_reacquire_s or np.inf))
        if lost.any():
            start = _ik_state(kf.model, np.where(present[:, None], positions, np.nan))
            kf.reacquire(np.flatnonzero(lost), start)
            self.gated_since[lost] = np.nan
        used = kf.update_joints(np.where(observed, z, np.nan), observed, R_diag, self.config.online_gate_chi2)
        self.n_gated += int(present.sum() - used.sum())
        since = np.where(used, np.nan, self.gated_since)  # a joint that entered ends its run
        self.gated_since = np.where(present & ~used, np.fmin(since, t), since)


def live_filter(config: PipelineConfig) -> OnlineFilter | JointFilter:
    """Returns the causal filter a live count runs for recordings with these settings: the joints filter's forward
    pass where the offline output is the joints filter (the webcam: the live count and the stored count are then
    counted on the same positions, kinect_agent.analysis.live.counting_positions), else the chain's (OnlineFilter)."""
    return JointFilter(config) if config.offline_filter == "joints" else OnlineFilter(config)


def run_online(
    rec: Recording, config: PipelineConfig, progress: Progress | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, km.ChainModel, dict[str, Any]]:
    """Runs OnlineFilter over all frames; returns its estimates per frame against the final references.

    Returns root (T, 3) m, lengths (19,) m, theta (T, 33) rad, the chain model (final references) and info
    {"n_gated", "n_held"}. Frames before the filter starts take the first estimate. progress(done, total) now and
    then.
    """
    T = rec.n_frames
    filt = OnlineFilter(config)
    roots, thetas = np.full((T, 3), np.nan), np.full((T, N_TH), np.nan)
    refs: list[np.ndarray | None] = [None] * T
    for k in range(T):
        filt.step(float(rec.t[k]), rec.positions[k], rec.state[k])
        if filt.kf is not None:
            root, _, theta = filt.kf.split(filt.kf.x)
            roots[k], thetas[k] = root, theta
            refs[k] = filt.kf.model.R_ref.copy()
        if progress is not None and (k % 64 == 63 or k == T - 1):
            progress(k + 1, T)
    if filt.kf is None:
        raise ValueError("the trunk (ROOT, SPINE, HIP_L, HIP_R) is never tracked: the online filter cannot start")
    first = int(np.flatnonzero([r is not None for r in refs])[0])
    roots[:first], thetas[:first] = roots[first], thetas[first]
    for k in range(first):
        refs[k] = refs[first]
    filt.fix_lengths()
    kf = filt.kf
    if kf.lengths is None:  # fix_lengths has just fixed them
        raise ProcessingError("the online filter's segment lengths are still in its state after fix_lengths")
    # Re-centring changes the references over time: express every frame against the final references.
    model = kf.model
    thetas = model.rebase(thetas, np.array(refs))
    return roots, kf.lengths, thetas, model, {"n_gated": filt.n_gated, "n_held": filt.n_held}


__all__ = ["OnlineFilter", "live_filter", "run_online"]
