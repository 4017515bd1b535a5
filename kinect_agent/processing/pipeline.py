"""The signal pipeline of the home agent: outlier removal, then the four-pass kinematic UKF (Wang et al., §3.2, §4).

    rec ──combined_outliers: temporal mixture (outliers.py) + sustained excursions (excursions.py)──> clean
        (tracking-loss samples -> missing)
        ──ik.inverse_kinematics────> personalised chain + start values
        ──pass 1 forward UKF, pass 2 backward UKF (state: root, 19 lengths, 33 joint angles; x(t) = x(t±1) + δ)
        ──lengths fixed (removed from the state: covariance and process noise zero)
        ──pass 3 forward UKF, then either (config.smoother)
              "urts" (default): the unscented RTS smoother (Särkkä 2008) run backwards over pass 3's estimates; for
                           the random-walk transition it is exact. Measured better than "four_pass" on simulated
                           motion with known truth (RMSE 15.5 vs 16.5-17.5 mm at 30 Hz, 1.5 cm noise).
              "four_pass": the paper's pass 4, a backward UKF started from pass 3's end. Output (four_pass_combine):
                           "last" = pass 4 itself (default), or "information" = per frame the information-weighted
                           mean of passes 3 and 4 (P = (P3⁻¹ + P4⁻¹)⁻¹, x = P (P3⁻¹ x3 + P4⁻¹ x4)); the latter is
                           slightly better on simulated motion but unstable on real recordings where the two passes
                           settle on different but equivalent joint-angle branches (averaging angles then fails).
        ──forward kinematics──> filtered Recording (every joint of every frame) + KinematicParams + quality.

State per frame (ChainModel of kinematics.py): root position (3, m), segment lengths (19, m; passes 1-2 only) and
33 joint angles (rad): rotation vectors relative to per-sequence reference rotations for the 3-DoF joints, hinge
angles for elbows/knees, two angles for wrists/ankles. Observation: the 20 joint positions (60 values); per frame
only observed joints enter (rows of z and R selected), tracked joints with SD sigma_tracked_m per axis, inferred
joints with sigma_inferred_m. Process noise is a random walk scaled with the frame interval: Q = q² · dt · rate_ref
(offline: offline_q_rot_rad / offline_q_root_m in place of q_rot_rad / q_root_m),
with a variance ceiling (the initial variance) so that directions no joint observes cannot spread the sigma points
over several radians. Joints whose innovation is improbable (d² > gate_chi2 for one joint) are skipped in that step.
A joint skipped for reacquire_s without a break has lost track rather than met an outlier (the gate is relative to
the state's own spread, so a limb that once outruns the random walk, e.g. a knee at 20-30°/frame in a deep squat,
would stay gated for good): the angles that place it restart from inverse kinematics of that frame with the initial
variance, and the gate admits it again.
Passes 1-2 use the first length_pass_max_frames frames of longer recordings (they only estimate the lengths).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from kinect_agent import skeleton
from kinect_agent.blas_threads import one_blas_thread
from kinect_agent.processing import _ukf_numba
from kinect_agent.processing import kinematics as km
from kinect_agent.processing.angles import joint_angles
from kinect_agent.processing.combined_outliers import remove_outliers_combined
from kinect_agent.processing.excursions import LiveExcursions
from kinect_agent.processing.ik import IKResult, bone_length_estimate, inverse_kinematics
from kinect_agent.processing.params import KinematicParams
from kinect_agent.processing.rotations import matrix_to_quat, matrix_to_rotvec
from kinect_agent.processing.ukf import (
    MerweScaledSigmaPoints,
    UnscentedKalmanFilter,
    combine_information,
    gated_update,
    unscented_rts,
)
from kinect_agent.recording import Recording
from kinect_agent.skeleton import INFERRED, NOT_TRACKED, TRACKED

VERSION = "ukf-4pass v1"
SMOOTHERS = ("four_pass", "urts")
N_ROOT, N_LEN, N_TH = 3, km.N_BONES, km.N_THETA
Progress = Callable[[int, int], None]


@dataclass
class PipelineConfig:
    """Settings of the pipeline; defaults measured on simulated Kinect noise and real recordings (see the report)."""

    sigma_tracked_m: float = 0.0325  # measurement SD per axis of a tracked joint, m (offline; online has its own).
    # Kinect's error is slow jitter (AR(1), τ 0.2 s) plus bias, so trusting single frames (0.015 m before 2026-11-24)
    # passes the jitter through. Chosen with offline_q_rot_rad / offline_q_root_m below (bench/README.md).
    sigma_inferred_m: float = 0.05  # measurement SD per axis of an inferred joint (state 1), m
    q_root_m: float = 0.01  # random-walk SD of the root position per frame at rate_ref_hz, m
    q_rot_rad: float = 0.08  # random-walk SD of every joint angle per frame at rate_ref_hz, rad
    offline_q_rot_rad: float | None = 0.13  # offline (smooth): q_rot_rad of the four passes (None: q_rot_rad)
    offline_q_root_m: float | None = 0.012  # offline (smooth): q_root_m of the four passes (None: q_root_m).
    # Raising R and Q together keeps fast real limbs followed while root and joints average more jitter (relative to
    # the inferred joints' SD and the variance ceilings). Tuning set (simulator + CMU), pooled offline RMSE / elbow-
    # knee angle RMSE: old (0.015 m, 0.08 rad, 0.01 m) 122.7 mm / 24.3°; now (0.0325, 0.13, 0.012) 118.2 mm / 24.1°.
    # Bounded by real data: 0.07 m (q unchanged) gave 117.1 mm / 23.1° but lagged UI-PRMD knees (median |filtered -
    # raw| up to 16°, bound 5°); 0.035-0.04 m with q_rot 0.14-0.16 gave 117.3-117.8 mm but the UI-PRMD m09 elbow
    # lost its correlation with raw (0.942-0.948, bound 0.95) and q_rot 0.16 fills a 0.5 s gap 115 mm off (bound
    # 100; now 90); 0.03 m, 0.12 rad: 118.8 mm, behind One Euro at Kinect 1 30°/60°. Innovation gate none / 30 /
    # 100, sigma_inferred_m and four_pass changed little or lost (q_* / sigma_inferred_m are shared with online).
    q_length_m: float = 0.001  # random-walk SD of segment lengths per frame (passes 1-2), m
    p0_root_m: float = 0.05  # initial SD of the root position, m
    p0_rot_rad: float = 0.3  # initial SD of the joint angles, rad
    p0_length_m: float = 0.03  # initial SD of segment lengths, m
    rate_ref_hz: float = 30.0  # the rate at which the q_* values are per frame
    remove_outliers: bool = True  # run the mixture-model outlier removal first
    outlier_threshold: float = 0.95  # outlier when P(uniform component) exceeds this; 0.95 rather than the MAP 0.5:
    # the precision/recall operating point (tuning set, simulator + CMU: precision 0.92 vs 0.90 at 0.5, recall 0.97)
    outlier_window_s: float = 0.5  # window of the outlier residual's running median / local quadratic fit, s;
    # 0.5 s (15 frames at 30 Hz) outlasts twice the longest tracking-loss burst (0.2 s) yet follows fast motion:
    # on the tuning set (simulator + CMU, Kinect 2 0°/30°, Kinect 1 60°) precision 0.90 / recall 0.98 where
    # 0.7 s gave 0.83 / 0.99 (turning points of fast motion flagged) and 0.3 s 0.85 / 0.95; see bench/README.md
    outlier_min_sigma_m: float = 0.015  # floor of the Gaussian's SD per axis: Kinect's random error (paper §3.1,
    # joint offset SD ≈ 20 mm) — keeps still, clean stretches from making ordinary motion look like outliers
    outlier_min_range_m: float = 1.0  # floor of the uniform component's range per axis (tracking loss throws a
    # joint anywhere in view); Gaussian weights are kept >= 0.5 (outliers are the minority)
    outlier_iterations: int = 2  # local-quadratic refinements of the outlier residual after the median stage
    outlier_segment: str | None = None  # "max"/"or": also a segment-length-deviation residual (segment_outliers.py)
    # combined with the temporal one; None (default): temporal only — real pairs gain, simulated precision drops
    outlier_excursions: bool = True  # also flag sustained excursions (excursions.py): a joint that jumps away faster
    # than a body moves, sits there and jumps back; real KERAAL pairs RMSE 128.6 -> 76.3 mm, simulated precision
    # 0.916 -> 0.913 (bench/README.md)
    online_excursions: bool = True  # the online filter holds out a joint from an abrupt jump away until it jumps
    # back, travels or excursion_max_len_s passes (excursions.LiveExcursions): real KERAAL pairs online RMSE 134.9 ->
    # 92.7 mm, elbow 36.2 -> 18.0 deg; simulated 121.9 -> 123.6 mm (still below every causal baseline per setting)
    excursion_min_dev_m: float = 0.2  # an excursion's jump away and its median distance from the bridge, at least
    excursion_min_len_s: float = 0.3  # shorter ones are left to the temporal residual (its 0.5 s window)
    excursion_max_len_s: float = 3.0  # longest excursion searched for
    gate_chi2: float | None = 30.0  # drop a joint whose innovation d² exceeds this (None: never); online always
    reacquire_s: float | None = 0.1  # a joint gated this long without a break is a lost track, not an outlier: the
    # angles that place it restart from inverse kinematics of the frame (None: never). Without it a fast limb
    # (UI-PRMD squat: knee 20-30°/frame) outruns the random walk once and is then gated for good.
    online_reacquire_s: float | None = 0.3  # the same for the online filter when online_gate_chi2 is set
    online_sigma_tracked_m: float = 0.07  # online: measurement SD per axis of a tracked joint, m. Tuned before
    # offline's (then 0.015 m): with no backward pass the forward filter alone must average Kinect's slow jitter
    # (AR(1), τ 0.2 s, SDs up to 0.1 m) and ride out tracking-loss bursts. Tuning set (simulator + CMU), pooled
    # online RMSE: 0.015 m 128.3 mm, 0.03 m 123.4, 0.05 m 120.9, 0.07 m 119.3, 0.1 m 119.0 (worse on CMU); raw 140.6.
    online_gate_chi2: float | None = None  # online: the UKF's innovation gate on one joint's d² (None: no gate).
    # Measured worse than none (tuning set: 30 → 135.0 mm, 100 → 127.4, none 128.3 at the old 0.015 m; at 0.05 m
    # 60 → 121.3, none 120.9): the gate is relative to the state's spread and drops fast limbs (CMU arms: a tenth of
    # the joint-frames gated at 30), which then lag for online_reacquire_s; a causal Gaussian + uniform test
    # against the predicted joints (hidden Markov burst prior) was tried too and did not beat none (121.3 vs
    # 120.9 at its best operating point). With a loose R the bursts pull the state by a fraction of their offset.
    smoother: str = "urts"  # "urts" (unscented RTS after pass 3; measured best) or "four_pass" (paper: pass 4 backward)
    four_pass_combine: str = "last"  # four_pass output: "last" (pass 4) or "information" (passes 3+4 averaged)
    alpha: float = 0.5  # sigma-point spread (van der Merwe)
    beta: float = 2.0
    kappa: float = 0.0
    length_pass_max_frames: int | None = 6000  # passes 1-2 (length estimation) run over at most this many first
    # frames (200 s at 30 Hz); None = every frame (the paper exactly). Passes 3-4 always use every frame.
    online_init_s: float = 1.0  # online: segment lengths are estimated over this first stretch, then fixed
    extra: dict[str, Any] = field(default_factory=dict)

    def check(self) -> None:
        """Raises ValueError naming the first setting out of range."""
        for name in ("sigma_tracked_m", "sigma_inferred_m", "q_root_m", "q_rot_rad", "p0_root_m", "p0_rot_rad",
                     "p0_length_m", "rate_ref_hz", "outlier_window_s", "alpha", "excursion_min_dev_m",
                     "excursion_min_len_s"):  # fmt: skip
            if not getattr(self, name) > 0:
                raise ValueError(f"PipelineConfig.{name} must be > 0, got {getattr(self, name)!r}")
        if self.q_length_m < 0:
            raise ValueError(f"PipelineConfig.q_length_m must be >= 0, got {self.q_length_m!r}")
        if not 0.0 < self.outlier_threshold < 1.0:
            raise ValueError(f"PipelineConfig.outlier_threshold must be in (0, 1), got {self.outlier_threshold!r}")
        if not self.excursion_max_len_s > self.excursion_min_len_s:
            raise ValueError(f"PipelineConfig.excursion_max_len_s must exceed excursion_min_len_s, "
                             f"got {self.excursion_max_len_s!r}")  # fmt: skip
        if self.outlier_segment not in (None, "max", "or"):
            raise ValueError(
                f"PipelineConfig.outlier_segment must be None, 'max' or 'or', got {self.outlier_segment!r}"
            )
        if self.smoother not in SMOOTHERS:
            raise ValueError(f"PipelineConfig.smoother must be one of {SMOOTHERS}, got {self.smoother!r}")
        if self.gate_chi2 is not None and not self.gate_chi2 > 0:
            raise ValueError(f"PipelineConfig.gate_chi2 must be > 0 or None, got {self.gate_chi2!r}")
        if not self.online_sigma_tracked_m > 0:
            raise ValueError(f"PipelineConfig.online_sigma_tracked_m must be > 0, got {self.online_sigma_tracked_m!r}")
        if self.online_gate_chi2 is not None and not self.online_gate_chi2 > 0:
            raise ValueError(f"PipelineConfig.online_gate_chi2 must be > 0 or None, got {self.online_gate_chi2!r}")
        for name in ("offline_q_rot_rad", "offline_q_root_m"):
            if getattr(self, name) is not None and not getattr(self, name) > 0:
                raise ValueError(f"PipelineConfig.{name} must be > 0 or None, got {getattr(self, name)!r}")
        for name in ("reacquire_s", "online_reacquire_s"):
            if getattr(self, name) is not None and not getattr(self, name) > 0:
                raise ValueError(f"PipelineConfig.{name} must be > 0 or None, got {getattr(self, name)!r}")


@dataclass
class PipelineResult:
    """filtered: same frames and times as the input, every joint filled (state 2 observed, 1 filled by the model).

    params: kinematic parameters. quality: outlier_fraction {joint: fraction of present samples removed},
    segment_sd_before_mm / segment_sd_after_mm {segment: SD of its length}, frames_without_observation,
    n_frames, n_outliers, n_gated, smoother, online, seconds.
    """

    filtered: Recording
    params: KinematicParams
    quality: dict[str, Any]


# ----------------------------------------------------------------------------------------------------- filtering


def _observations(rec: Recording, config: PipelineConfig) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Returns z (T, 60) m, observed (T, 60) bool, R_diag (T, 60) m² from a recording (missing rows NaN/False)."""
    T = rec.n_frames
    z = rec.positions.reshape(T, -1)
    obs = np.repeat(rec.state != NOT_TRACKED, 3, axis=1) & np.isfinite(z)
    sd = np.where(rec.state == INFERRED, config.sigma_inferred_m, config.sigma_tracked_m)
    return z, obs, np.repeat(sd**2, 3, axis=1)


class _Chain:
    """Observation functions of the chain on sigma points: full state (root, lengths, theta) or lengths fixed."""

    def __init__(self, model: km.ChainModel, lengths: np.ndarray | None) -> None:
        self.model, self.lengths = model, lengths
        self._buf: np.ndarray | None = None
        self._len: np.ndarray | None = None
        # For the fused kernel (_ukf_numba.chain_step): the fixed lengths, or zeros while lengths are in the state.
        self.n_len = 0 if lengths is not None else N_LEN
        self.fixed_lengths = np.zeros(N_LEN) if lengths is None else np.ascontiguousarray(lengths, dtype=np.float64)

    @property
    def dim(self) -> int:
        return N_ROOT + N_TH + (0 if self.lengths is not None else N_LEN)

    def split(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Returns (root (..., 3), lengths (..., 19), theta (..., 33)) from states x (..., dim)."""
        if self.lengths is not None:
            return x[..., :N_ROOT], np.broadcast_to(self.lengths, x.shape[:-1] + (N_LEN,)), x[..., N_ROOT:]
        return x[..., :N_ROOT], x[..., N_ROOT : N_ROOT + N_LEN], x[..., N_ROOT + N_LEN :]

    def hx(self, sig: np.ndarray) -> np.ndarray:
        """Returns the joint positions (S, 60) m for states sig (S, dim)."""
        if km._fk_numba.AVAILABLE and self.model.compiled and sig.ndim == 2:
            S = sig.shape[0]
            if self._buf is None or self._buf.shape[0] != S:
                self._buf = np.empty((S, skeleton.J, 3))
                self._len = None if self.lengths is None else np.ascontiguousarray(np.tile(self.lengths, (S, 1)))
            root, lengths, theta = self.split(sig)
            lengths = self._len if self._len is not None else lengths
            km._fk_numba.fk_many(root, lengths, theta, self.model.rest, self.model.R_ref, *km._KERNEL_TABLES, self._buf)
            return self._buf.reshape(S, -1)
        root, lengths, theta = self.split(sig)
        return self.model.positions(root, lengths, theta).reshape(sig.shape[:-1] + (3 * skeleton.J,))

    def q_diag(self, config: PipelineConfig) -> np.ndarray:
        parts = [np.full(N_ROOT, config.q_root_m**2)]
        if self.lengths is None:
            parts.append(np.full(N_LEN, config.q_length_m**2))
        parts.append(np.full(N_TH, config.q_rot_rad**2))
        return np.concatenate(parts)

    def p0_diag(self, config: PipelineConfig) -> np.ndarray:
        parts = [np.full(N_ROOT, config.p0_root_m**2)]
        if self.lengths is None:
            parts.append(np.full(N_LEN, config.p0_length_m**2))
        parts.append(np.full(N_TH, config.p0_rot_rad**2))
        return np.concatenate(parts)


def _make_filter(chain: _Chain, config: PipelineConfig) -> UnscentedKalmanFilter:
    n = chain.dim
    pts = MerweScaledSigmaPoints(n, config.alpha, config.beta, config.kappa)
    kf = UnscentedKalmanFilter(n, 3 * skeleton.J, chain.hx, fx=None, points=pts)
    kf.P0_ceiling = chain.p0_diag(config)  # variance ceiling of the random walk (see _add_process_noise)
    kf.kernel_weights = np.array([pts.scale, pts.Wm[0], pts.Wm[1], pts.Wc[0], pts.Wc[1]])  # for _ukf_numba
    return kf


def _update(
    kf: UnscentedKalmanFilter, z: np.ndarray, observed: np.ndarray, R_diag: np.ndarray, gate_chi2: float | None
) -> np.ndarray:
    """One gated UKF update of the chain (ukf.gated_update); one fused compiled kernel when numba is installed.

    z (60,) m, NaN allowed where not observed; observed (60,) bool; R_diag (60,) m². Returns (20,) bool used joints.
    """
    chain: _Chain = kf.hx.__self__
    gate = np.inf if gate_chi2 is None else float(gate_chi2)
    if _ukf_numba.AVAILABLE and km._fk_numba.AVAILABLE and chain.model.compiled:
        x, P = kf.x, kf.P
        if not (x.dtype == np.float64 and x.flags.c_contiguous and x.flags.writeable):
            kf.x = x = np.array(x, dtype=np.float64)
        if not (P.dtype == np.float64 and P.flags.c_contiguous and P.flags.writeable):
            kf.P = P = np.array(P, dtype=np.float64)
        w = getattr(kf, "kernel_weights", None)
        if w is None:
            pts = kf.points
            kf.kernel_weights = w = np.array([pts.scale, pts.Wm[0], pts.Wm[1], pts.Wc[0], pts.Wc[1]])
        used = np.empty(skeleton.J, dtype=bool)
        status = _ukf_numba.chain_step(
            x, P, z, observed, R_diag, w, gate, chain.fixed_lengths, chain.n_len,
            chain.model.rest, chain.model.R_ref, km.STEP_TABLES, used,
        )  # fmt: skip
        if status == _ukf_numba.OK:
            return used
        # P or S not positive definite (x, P untouched): the numpy path below adds jitter.
    groups = (np.asarray(observed, dtype=bool) & np.isfinite(z)).reshape(-1, 3).all(axis=1)
    return gated_update(kf, np.where(np.isfinite(z), z, 0.0), np.repeat(groups, 3), R_diag, gate)


def _add_process_noise(P: np.ndarray, diag: np.ndarray, q: np.ndarray, ceiling: np.ndarray) -> None:
    """Adds the random-walk variance q (n,) to the diagonal of P (n, n), but never beyond `ceiling` (n,).

    Directions the joints do not observe (e.g. how a twist splits between SPINE and NECK, a hand's roll) would
    otherwise grow without bound, spreading the sigma points over several radians where F is far from linear;
    observed directions have variances far below the ceiling, so for them this is the plain random walk.
    """
    if _ukf_numba.AVAILABLE and P.dtype == np.float64 and diag.dtype == np.int64:
        _ukf_numba.add_capped(P, diag, np.asarray(q, dtype=np.float64), np.asarray(ceiling, dtype=np.float64))
        return
    P[diag, diag] += np.minimum(q, np.maximum(ceiling - P[diag, diag], 0.0))


def _placing_entries() -> tuple[np.ndarray, ...]:
    """Returns, per joint, the state entries (offsets into root (3) + theta (33)) that place it relative to the trunk.

    ROOT: the root position. Others: the angles of their rotating ancestors below ROOT (ANK_L: the KNE_L hinge and
    the HIP_L rotation); none for the joints that hang from ROOT itself (SPINE, HIP_*): ROOT's rotation turns the
    whole body, and one frame's inverse kinematics can have it flipped by about π in fast motion (HDM05 arm circles:
    a hip gated for 0.1 s restarted it and threw the arms 1.3 m off), so it is never restarted.
    """
    out = [np.arange(N_ROOT)]
    for j in range(1, skeleton.J):
        rots, p = [], int(skeleton.PARENT[j])
        while p > 0:
            rots.append(km.ROT_INDEX[p])
            p = int(skeleton.PARENT[p])
        starts = [km.ROT_START[r] + np.arange(km.ROT_DOF[r]) for r in rots]
        out.append(N_ROOT + np.concatenate(starts) if starts else np.zeros(0, dtype=np.int64))
    return tuple(out)


_PLACING = _placing_entries()


def _reacquire(kf: UnscentedKalmanFilter, joints: np.ndarray, start: np.ndarray, p0: np.ndarray) -> None:
    """Restarts the state entries that place `joints` from `start` (root (3) m + theta (33) rad, e.g. IK of the frame).

    Their covariance becomes the initial one (p0 (n,), variances) with no correlation to the rest of the state.
    """
    entries = np.unique(np.concatenate([_PLACING[j] for j in joints]))
    idx = np.where(entries < N_ROOT, entries, entries + kf.dim_x - N_ROOT - N_TH)  # skip lengths in the state
    kf.x[idx] = start[entries]
    kf.P[idx, :] = 0.0
    kf.P[:, idx] = 0.0
    kf.P[idx, idx] = p0[idx]


def _ik_state(model: km.ChainModel, positions: np.ndarray) -> np.ndarray:
    """Returns (36,) root (m) + theta (rad) of one frame by inverse kinematics, against `model`'s references.

    positions: (J, 3) m, camera frame, NaN = untracked.
    """
    ik = inverse_kinematics(positions[None])
    theta = ik.theta[0].copy()
    R = ik.model.local_rotations(theta)[km._R3]  # (7, 3, 3) local rotations of the 3-DoF joints
    theta[km.THETA_3DOF] = matrix_to_rotvec(np.swapaxes(model.R_ref, -1, -2) @ R).reshape(-1)
    return np.concatenate((ik.root[0], theta))


def _run_pass(
    kf: UnscentedKalmanFilter,
    order: np.ndarray,
    obs: tuple[np.ndarray, np.ndarray, np.ndarray],
    q_steps: np.ndarray,
    config: PipelineConfig,
    store: bool,
    tick: Callable[[int], None],
    restart: tuple[np.ndarray, int] | None = None,
) -> tuple[np.ndarray | None, np.ndarray | None, int]:
    """Runs one filter pass over frames in `order`; returns (xs (T, n), Ps (T, n, n)) in frame order if stored.

    q_steps: (T,) scale of Q (dt · rate_ref) for the step into each frame of `order` (first frame: no predict).
    restart: (start (T, 36) root m + theta rad per frame, e.g. from IK; n_frames): a joint the gate dropped in
    n_frames consecutive observed frames has lost track, and the entries that place it restart from `start` at the
    next frame it is observed (_reacquire). Returns also the number of joint samples dropped by the innovation gate.
    """
    z, observed, R_diag = obs
    n = kf.dim_x
    T = len(order)
    xs = np.empty((T, n)) if store else None
    Ps = np.empty((T, n, n)) if store else None
    qd = kf.Q.diagonal().copy()
    ceiling = kf.P0_ceiling if hasattr(kf, "P0_ceiling") else np.full(n, np.inf)
    diag = np.arange(n)
    gated = 0
    run = np.zeros(skeleton.J, dtype=np.int64)  # consecutive observed frames each joint was gated
    for i, k in enumerate(order):
        if i:
            _add_process_noise(kf.P, diag, qd * q_steps[i], ceiling)
        if observed[k].any():
            present = observed[k].reshape(-1, 3).all(axis=1)
            if restart is not None:
                lost = present & (run >= restart[1])
                if lost.any():
                    _reacquire(kf, np.flatnonzero(lost), restart[0][k], ceiling)
                    run[lost] = 0
            used = _update(kf, z[k], observed[k], R_diag[k], config.gate_chi2)
            gated += int(present.sum() - used.sum())
            run = np.where(used, 0, run + (present & ~used))
        if store:
            xs[k] = kf.x
            Ps[k] = kf.P
        if i % 64 == 63:
            tick(64)
    tick(T % 64)
    return xs, Ps, gated


def _step_scales(t: np.ndarray, config: PipelineConfig) -> np.ndarray:
    """Returns (T,) the Q scale for stepping into frame k from frame k−1: dt · rate_ref (entry 0 unused)."""
    dt = np.diff(t, prepend=t[0] - 1.0 / config.rate_ref_hz)
    return np.maximum(dt, 1e-6) * config.rate_ref_hz


def smooth(
    clean: Recording, ik: IKResult, config: PipelineConfig, progress: Progress | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
    """Runs the four passes on an outlier-free recording; returns (root (T, 3), lengths (19,), theta (T, 33), info)."""
    config = replace(
        config,
        q_rot_rad=config.q_rot_rad if config.offline_q_rot_rad is None else config.offline_q_rot_rad,
        q_root_m=config.q_root_m if config.offline_q_root_m is None else config.offline_q_root_m,
    )
    T = clean.n_frames
    total = 4 * T
    done = [0]

    def tick(k: int) -> None:
        done[0] += k
        if progress is not None and k:
            progress(min(done[0], total), total)

    obs = _observations(clean, config)
    scale = _step_scales(clean.t, config)
    fwd, bwd = np.arange(T), np.arange(T - 1, -1, -1)
    scale_bwd = np.concatenate(([0.0], scale[1:][::-1]))  # stepping from k+1 back to k uses dt of k+1
    # Passes 1 and 2: lengths in the state, over the first length_pass_max_frames frames (the lengths are constants
    # of the body; a contiguous stretch keeps the frame rate the angles were tuned for, which subsampling did not).
    n_len = T if not config.length_pass_max_frames else min(T, config.length_pass_max_frames)
    sub = np.arange(n_len)
    obs_sub = tuple(a[sub] for a in obs)
    scale_sub = scale[sub]
    scale_sub_bwd = np.concatenate(([0.0], scale_sub[1:][::-1]))
    n_sub = len(sub)
    restart = None
    if config.reacquire_s is not None and config.gate_chi2 is not None:
        dt = np.median(np.diff(clean.t)) if T > 1 else 1.0 / config.rate_ref_hz
        restart = (np.concatenate((ik.root, ik.theta), axis=1), max(1, int(round(config.reacquire_s / dt))))
    total = 2 * n_sub + 2 * T
    full = _Chain(ik.model, None)
    kf = _make_filter(full, config)
    kf.x = np.concatenate((ik.root[0], ik.lengths, ik.theta[0]))
    kf.P = np.diag(full.p0_diag(config))
    kf.Q = np.diag(full.q_diag(config))
    _, _, g1 = _run_pass(kf, np.arange(n_sub), obs_sub, scale_sub, config, False, tick, restart)
    _, _, g2 = _run_pass(kf, np.arange(n_sub - 1, -1, -1), obs_sub, scale_sub_bwd, config, False, tick, restart)
    lengths = kf.x[N_ROOT : N_ROOT + N_LEN].copy()
    # A bone seen too rarely can wander (even below zero); keep the measured median length there.
    implausible = ~((lengths > 0.5 * ik.lengths) & (lengths < 2.0 * ik.lengths))
    lengths[implausible] = ik.lengths[implausible]
    length_sd = np.sqrt(np.diag(kf.P)[N_ROOT : N_ROOT + N_LEN])
    # Passes 3 and 4: lengths fixed (removed from the state: zero covariance and process noise).
    keep = np.r_[0:N_ROOT, N_ROOT + N_LEN : N_ROOT + N_LEN + N_TH]
    fixed = _Chain(ik.model, lengths)
    kf3 = _make_filter(fixed, config)
    kf3.x = kf.x[keep].copy()
    kf3.P = kf.P[np.ix_(keep, keep)].copy()
    kf3.Q = np.diag(fixed.q_diag(config))
    xs3, Ps3, g3 = _run_pass(kf3, fwd, obs, scale, config, True, tick, restart)
    if config.smoother == "urts":
        Qs = np.einsum("t,ij->tij", np.append(scale[1:], 0.0), kf3.Q)
        xs, _ = unscented_rts(xs3, Ps3, Qs, None, kf3.points)
        tick(T)
        g4 = 0
    else:
        kf4 = _make_filter(fixed, config)
        kf4.x, kf4.P, kf4.Q = kf3.x.copy(), kf3.P.copy(), kf3.Q
        xs4, Ps4, g4 = _run_pass(kf4, bwd, obs, scale_bwd, config, True, tick, restart)
        xs = xs4 if config.four_pass_combine == "last" else combine_information(xs3, Ps3, xs4, Ps4)[0]
    info = {"length_sd_m": length_sd, "gated_per_pass": [g1, g2, g3, g4], "length_pass_frames": n_len}
    return xs[:, :N_ROOT], lengths, xs[:, N_ROOT:], info


# ----------------------------------------------------------------------------------------------------- online


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
    """

    def __init__(self, config: PipelineConfig | None = None, lengths: np.ndarray | None = None) -> None:
        self.config = config or PipelineConfig()
        self.config.check()
        if lengths is not None:
            lengths = np.asarray(lengths, dtype=np.float64)
            if lengths.shape != (N_LEN,):
                raise ValueError(f"lengths must have shape ({N_LEN},), got {lengths.shape}")
            if not np.all(np.isfinite(lengths) & (lengths > 0)):
                raise ValueError("lengths must be finite and > 0 metres")
        self.given_lengths = lengths
        self.kf: UnscentedKalmanFilter | None = None
        self.chain: _Chain | None = None
        self.t0: float | None = None
        self.t_last: float | None = None
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
        return self.chain is not None and self.chain.lengths is not None

    def _start(self, t: float, positions: np.ndarray) -> None:
        # One frame starts the filter: a joint whose bone to its parent is implausible (an outlier in this very
        # frame) is left out, so that IK places it at a typical offset instead of anchoring the state on it.
        reference = self.given_lengths if self.given_lengths is not None else km.TYPICAL_LENGTHS
        bone = skeleton.bone_lengths(positions)
        odd = ~((bone > 0.5 * reference) & (bone < 2.0 * reference)) & np.isfinite(bone)
        positions = positions.copy()
        positions[1:][odd] = np.nan
        ik = inverse_kinematics(positions[None])
        lengths = self.given_lengths
        chain = _Chain(ik.model, lengths)
        kf = _make_filter(chain, self.config)
        parts = [ik.root[0]] + ([] if lengths is not None else [ik.lengths]) + [ik.theta[0]]
        kf.x = np.concatenate(parts)
        kf.P = np.diag(chain.p0_diag(self.config))
        kf.Q = np.diag(chain.q_diag(self.config))
        self.kf, self.chain, self.t0, self.t_last = kf, chain, t, t

    def _fix_lengths(self) -> None:
        kf, chain = self.kf, self.chain
        keep = np.r_[0:N_ROOT, N_ROOT + N_LEN : N_ROOT + N_LEN + N_TH]
        fixed = _Chain(chain.model, kf.x[N_ROOT : N_ROOT + N_LEN].copy())
        kf2 = _make_filter(fixed, self.config)
        kf2.x, kf2.P = kf.x[keep].copy(), kf.P[np.ix_(keep, keep)].copy()
        kf2.Q = np.diag(fixed.q_diag(self.config))
        self.kf, self.chain = kf2, fixed

    def _recentre(self) -> None:
        """Folds large 3-DoF rotation vectors into the references so they stay far from ±π."""
        from kinect_agent.processing.kinematics import _R3, THETA_3DOF, _rodrigues

        off = self.kf.dim_x - N_TH
        v = self.kf.x[off + THETA_3DOF].reshape(len(_R3), 3)
        big = np.linalg.norm(v, axis=1) > 1.5
        if big.any():
            model = self.chain.model
            model.R_ref[big] = model.R_ref[big] @ _rodrigues(v[big])
            v[big] = 0.0
            self.kf.x[off + THETA_3DOF] = v.reshape(-1)

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
        if self.t_last is not None and t <= self.t_last:
            raise ValueError(f"t must increase: got {t} after {self.t_last}")
        present = (state != NOT_TRACKED) & np.all(np.isfinite(positions), axis=1)
        if self.excursions is not None:
            held = self.excursions.step(t, positions, present)
            self.n_held += int(held.sum())
            present &= ~held
        if self.kf is None:
            trunk = [skeleton.INDEX[n] for n in ("ROOT", "SPINE", "HIP_L", "HIP_R")]
            if not present[trunk].all():
                out = np.where(present[:, None], positions, self.last)
                self.last = out
                return out.copy()
            self._start(t, np.where(present[:, None], positions, np.nan))
        else:
            if not self.lengths_fixed and t - self.t0 >= self.config.online_init_s:
                self._fix_lengths()
            dt_scale = max(t - self.t_last, 1e-6) * self.config.rate_ref_hz
            n = self.kf.dim_x
            _add_process_noise(self.kf.P, np.arange(n), self.kf.Q.diagonal() * dt_scale, self.kf.P0_ceiling)
        self.t_last = t
        z = positions.reshape(-1)
        observed = np.repeat(present, 3)
        sd = np.where(state == INFERRED, self.config.sigma_inferred_m, self.config.online_sigma_tracked_m)
        R_diag = np.repeat(sd**2, 3)
        if observed.any():
            lost = present & (t - self.gated_since >= (self.config.online_reacquire_s or np.inf))
            if lost.any():
                start = _ik_state(self.chain.model, np.where(present[:, None], positions, np.nan))
                _reacquire(self.kf, np.flatnonzero(lost), start, self.kf.P0_ceiling)
                self.gated_since[lost] = np.nan
            used = _update(self.kf, np.where(observed, z, np.nan), observed, R_diag, self.config.online_gate_chi2)
            self.n_gated += int(present.sum() - used.sum())
            since = np.where(used, np.nan, self.gated_since)  # a joint that entered ends its run
            self.gated_since = np.where(present & ~used, np.fmin(since, t), since)
        self._recentre()
        root, lengths, theta = self.chain.split(self.kf.x)
        out = self.chain.model.positions(root, lengths, theta)
        self.last = out
        return out


# ----------------------------------------------------------------------------------------------------- process


def _segment_sd_mm(positions: np.ndarray) -> dict[str, float]:
    seg = skeleton.segment_lengths(positions)
    with np.errstate(all="ignore"):
        ok = np.isfinite(seg).sum(axis=0) >= 2
        sd = np.where(ok, np.nanstd(np.where(ok, seg, 0.0), axis=0), np.nan) * 1000.0
    return {name: (float(v) if np.isfinite(v) else None) for name, v in zip(skeleton.SEGMENT_NAMES, sd, strict=True)}


def _check_input(rec: Recording) -> None:
    if not isinstance(rec, Recording):
        raise TypeError(f"process needs a Recording, got {type(rec).__name__}")
    if rec.n_frames < 1:
        raise ValueError("the recording has no frames")
    if not np.any(rec.state != NOT_TRACKED):
        raise ValueError("no joint is tracked in any frame of the recording: nothing to filter")


def process(
    rec: Recording,
    *,
    online: bool = False,
    config: PipelineConfig | None = None,
    progress: Progress | None = None,
) -> PipelineResult:
    """Filters a recording: outlier removal then the four-pass UKF (or, online=True, the forward pass only).

    rec: positions (T, J, 3) m, NaN = untracked; state (T, J). progress(done, total) is called now and then.
    Returns the filtered recording (same t), the kinematic parameters and a quality summary. Runs with one BLAS
    thread (kinect_agent.blas_threads), whatever the caller's environment says.
    """
    with one_blas_thread():
        return _process(rec, online=online, config=config, progress=progress)


def _process(
    rec: Recording, *, online: bool, config: PipelineConfig | None, progress: Progress | None
) -> PipelineResult:
    started = time.perf_counter()
    config = config or PipelineConfig()
    config.check()
    _check_input(rec)
    T = rec.n_frames
    if config.remove_outliers and not online:
        clean, prob = remove_outliers_combined(rec, config)
        outlier = (prob > config.outlier_threshold) & (rec.state != NOT_TRACKED)
    else:
        clean, prob, outlier = rec, np.where(rec.state == NOT_TRACKED, 1.0, 0.0), np.zeros((T, skeleton.J), bool)
    if online:
        root, lengths, theta, model, info = _online_run(clean, config, progress)
    else:
        ik = inverse_kinematics(clean.positions)
        root, lengths, theta, info = smooth(clean, ik, config, progress)
        model = ik.model
    positions = model.positions(root, np.broadcast_to(lengths, (T, N_LEN)), theta)
    if not np.all(np.isfinite(positions)):
        raise ValueError("the filter diverged (non-finite estimate); check the recording's units (metres expected)")
    observed = clean.state != NOT_TRACKED
    state = np.where(observed, TRACKED, INFERRED).astype(np.int8)
    mode = "online forward pass" if online else config.smoother
    step = f"{VERSION} ({mode}; {int(outlier.sum())} outliers removed)"
    filtered = rec.replace(step=step, positions=positions, state=state)
    R_world_root, R_local = model.standard_rotations(theta)
    params = KinematicParams(
        t=rec.t.copy(),
        segment_lengths=lengths,
        root=root,
        q_root=matrix_to_quat(R_world_root),
        q_local=matrix_to_quat(R_local),
        joint_angles=joint_angles(positions),
        outlier_prob=prob,
    )
    present = rec.state != NOT_TRACKED
    with np.errstate(all="ignore"):
        frac = np.where(present.sum(0) > 0, outlier.sum(0) / np.maximum(present.sum(0), 1), 0.0)
    quality = {
        "n_frames": T,
        "online": online,
        "smoother": None if online else config.smoother,
        "n_outliers": int(outlier.sum()),
        "outlier_fraction": {j: float(f) for j, f in zip(skeleton.JOINTS, frac, strict=True)},
        "frames_without_observation": int(np.sum(~observed.any(axis=1))),
        "segment_sd_before_mm": _segment_sd_mm(rec.positions),
        "segment_sd_after_mm": _segment_sd_mm(positions),
        "segment_lengths_m": {
            f"{skeleton.JOINTS[p]}-{skeleton.JOINTS[c]}": float(v)
            for (p, c), v in zip(skeleton.BONES, lengths, strict=True)
        },
        "n_gated": int(sum(info.get("gated_per_pass", [info.get("n_gated", 0)]))),
        "length_pass_frames": info.get("length_pass_frames"),
        "seconds": round(time.perf_counter() - started, 3),
    }
    return PipelineResult(filtered, params, quality)


def _online_run(
    rec: Recording, config: PipelineConfig, progress: Progress | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, km.ChainModel, dict[str, Any]]:
    """Runs OnlineFilter over all frames; returns its parameter estimates per frame (root, lengths, theta, model)."""
    T = rec.n_frames
    filt = OnlineFilter(config)
    roots, thetas = np.full((T, 3), np.nan), np.full((T, N_TH), np.nan)
    refs: list[np.ndarray | None] = [None] * T
    for k in range(T):
        filt.step(float(rec.t[k]), rec.positions[k], rec.state[k])
        if filt.kf is not None:
            root, _, theta = filt.chain.split(filt.kf.x)
            roots[k], thetas[k] = root, theta
            refs[k] = filt.chain.model.R_ref.copy()
        if progress is not None and (k % 64 == 63 or k == T - 1):
            progress(k + 1, T)
    if filt.kf is None:
        raise ValueError("the trunk (ROOT, SPINE, HIP_L, HIP_R) is never tracked: the online filter cannot start")
    first = int(np.flatnonzero([r is not None for r in refs])[0])
    roots[:first], thetas[:first] = roots[first], thetas[first]
    for k in range(first):
        refs[k] = refs[first]
    if not filt.lengths_fixed:
        filt._fix_lengths()
    lengths = filt.chain.lengths
    # Re-centring changes the references over time: express every frame against the final references.
    model = filt.chain.model
    thetas = _rebase(thetas, np.array(refs), model)
    return roots, lengths, thetas, model, {"n_gated": filt.n_gated, "n_held": filt.n_held}


def _rebase(theta: np.ndarray, refs: np.ndarray, model: km.ChainModel) -> np.ndarray:
    """Returns theta (T, 33) with 3-DoF rotation vectors re-expressed against model.R_ref (refs: (T, 7, 3, 3))."""
    from kinect_agent.processing.kinematics import _R3, THETA_3DOF, _rodrigues
    from kinect_agent.processing.rotations import matrix_to_rotvec

    T = len(theta)
    v = theta[:, THETA_3DOF].reshape(T, len(_R3), 3)
    R = refs @ _rodrigues(v)
    out = theta.copy()
    out[:, THETA_3DOF] = matrix_to_rotvec(np.swapaxes(model.R_ref, -1, -2) @ R).reshape(T, -1)
    return out


__all__ = ["OnlineFilter", "PipelineConfig", "PipelineResult", "bone_length_estimate", "process", "smooth"]
