"""The UKF of the kinematic chain (Wang et al., §4): its state layout, observation function and steps.

State (n,): root position (3, m), segment lengths (19, m; only while they are estimated) and the 33 joint angles
(rad) of kinematics.ChainModel. Observation: the 20 joint positions (60 values, m, camera frame) by forward
kinematics of every sigma point. Transition: the random walk, with the variance ceiling of predict_random_walk.
Update: UnscentedKalmanFilter.gated_update (per-joint innovation gate); when numba is installed and the model runs
the compiled forward kinematics, one fused kernel does the same step (_ukf_numba.chain_step; numpy stays the
reference and the fallback when the kernel finds a covariance that is not positive definite). run_frames runs a
stretch of a pass (predict, re-acquisition, update) in one compiled loop, the same steps as calling them per frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from kinect_agent import skeleton
from kinect_agent.body import kinematics as km
from kinect_agent.processing import _ukf_numba
from kinect_agent.processing.config import PipelineConfig
from kinect_agent.processing.ukf import MerweScaledSigmaPoints, UnscentedKalmanFilter

N_ROOT, N_LEN, N_TH = 3, km.N_BONES, km.N_THETA


def state_dim(lengths_fixed: bool) -> int:
    """Returns the state dimension: 36 with the segment lengths fixed, 55 with them in the state."""
    return N_ROOT + N_TH + (0 if lengths_fixed else N_LEN)


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
# _PLACING as one table for the compiled pass (_ukf_numba.run_frames): (J, 36) int64, -1 padded.
_PLACING_TABLE = np.full((skeleton.J, N_ROOT + N_TH), -1, dtype=np.int64)
for _j, _entries in enumerate(_PLACING):
    _PLACING_TABLE[_j, : len(_entries)] = _entries


@dataclass(frozen=True)
class FrameData:
    """A pass's observations, prepared once: z (T, 60) m, observed (T, 60) bool, R_diag (T, 60) m², present (T, J)
    bool (all three axes observed), n_present (T,) int, any_observed (T,) bool."""

    z: np.ndarray
    observed: np.ndarray
    R_diag: np.ndarray
    present: np.ndarray
    n_present: np.ndarray
    any_observed: np.ndarray

    @classmethod
    def of(cls, z: np.ndarray, observed: np.ndarray, R_diag: np.ndarray) -> FrameData:
        """Returns the frame data of z (T, 60), observed (T, 60), R_diag (T, 60)."""
        present = np.all(observed.reshape(len(observed), skeleton.J, 3), axis=2)
        return cls(z, observed, R_diag, present, present.sum(axis=1), np.any(observed, axis=1))

    def as_tuple(self) -> _ukf_numba.Observations:
        """Returns the arrays C-contiguous, in the order _ukf_numba.run_frames reads them."""
        c = np.ascontiguousarray
        return c(self.z), c(self.observed), c(self.R_diag), c(self.present), c(self.n_present), c(self.any_observed)


class ChainFilter(UnscentedKalmanFilter):
    """UKF over the chain's state: x (n,), P (n, n), Q (n, n) diagonal, with the initial variances as a ceiling.

    model: the chain (rest directions, 3-DoF references; used by reference, so re-centring the references shows).
    lengths: (19,) m fixed segment lengths, or None to carry them in the state.
    x: (n,) start state (root m, [lengths m], theta rad). P starts as diag(p0), Q is diag(q) from config.
    """

    def __init__(self, model: km.ChainModel, lengths: np.ndarray | None, config: PipelineConfig, x: np.ndarray) -> None:
        n = state_dim(lengths is not None)
        points = MerweScaledSigmaPoints(n, config.alpha, config.beta, config.kappa)
        super().__init__(n, 3 * skeleton.J, self.hx, fx=None, points=points)
        self.model, self.lengths = model, lengths
        # Variance ceiling of the random walk (predict_random_walk): the initial variances.
        self.p0_ceiling = self._diag_of(config.p0_root_m, config.p0_length_m, config.p0_rot_rad)
        self.x = np.array(x, dtype=np.float64)
        if self.x.shape != (n,):
            raise ValueError(f"x must have shape ({n},), got {self.x.shape}")
        self.P = np.diag(self.p0_ceiling)
        self.Q = np.diag(self._diag_of(config.q_root_m, config.q_length_m, config.q_rot_rad))
        # The fused kernel (_ukf_numba.chain_step): its weights, the fixed lengths (zeros while in the state).
        self.compiled = _ukf_numba.AVAILABLE and model.runs_compiled
        self.kernel_weights = np.array(
            [points.scale, points.Wm[0], points.Wm[1], points.Wc[0], points.Wc[1], float(config.innovation_at_mean)]
        )
        self.innovation_at_mean = config.innovation_at_mean
        self.n_len = 0 if lengths is not None else N_LEN
        self.fixed_lengths = np.zeros(N_LEN) if lengths is None else np.ascontiguousarray(lengths, dtype=np.float64)
        self._diag = np.arange(n)
        self._buf: np.ndarray | None = None  # hx's output buffer (S, J, 3) and tiled fixed lengths (S, 19)
        self._len: np.ndarray | None = None

    def _diag_of(self, root: float, length: float, rot: float) -> np.ndarray:
        """Returns (n,) squared SDs: root (3) m², [lengths (19) m²], theta (33) rad²."""
        parts = [np.full(N_ROOT, root**2)]
        if self.lengths is None:
            parts.append(np.full(N_LEN, length**2))
        parts.append(np.full(N_TH, rot**2))
        return np.concatenate(parts)

    def with_lengths_fixed(self, lengths: np.ndarray, config: PipelineConfig) -> ChainFilter:
        """Returns a filter on the same model without the lengths in its state (they become `lengths` (19,) m).

        Root and angles, and their covariance, are taken over; Q is that of config.
        """
        if self.lengths is not None:
            raise ValueError("the segment lengths are fixed already")
        keep = np.r_[0:N_ROOT, N_ROOT + N_LEN : N_ROOT + N_LEN + N_TH]
        fixed = ChainFilter(self.model, lengths, config, self.x[keep].copy())
        fixed.P = self.P[np.ix_(keep, keep)].copy()
        return fixed

    def copy(self, config: PipelineConfig) -> ChainFilter:
        """Returns an independent filter with the same model, lengths, x and P."""
        other = ChainFilter(self.model, self.lengths, config, self.x.copy())
        other.P = self.P.copy()
        return other

    def split(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Returns (root (..., 3), lengths (..., 19), theta (..., 33)) from states x (..., n)."""
        if self.lengths is not None:
            return x[..., :N_ROOT], np.broadcast_to(self.lengths, x.shape[:-1] + (N_LEN,)), x[..., N_ROOT:]
        return x[..., :N_ROOT], x[..., N_ROOT : N_ROOT + N_LEN], x[..., N_ROOT + N_LEN :]

    def theta(self) -> np.ndarray:
        """Returns the joint angles (33,) rad of the state, a view into x."""
        return self.x[self.dim_x - N_TH :]

    def positions(self) -> np.ndarray:
        """Returns the joint positions (J, 3) m, camera frame, of the current state."""
        root, lengths, theta = self.split(self.x)
        return self.model.positions(root, lengths, theta)

    def hx(self, sig: np.ndarray) -> np.ndarray:
        """Returns the joint positions (S, 60) m for states sig (S, n)."""
        if self.model.runs_compiled and sig.ndim == 2:
            S = sig.shape[0]
            if self._buf is None or self._buf.shape[0] != S:
                self._buf = np.empty((S, skeleton.J, 3))
                self._len = None if self.lengths is None else np.ascontiguousarray(np.tile(self.lengths, (S, 1)))
            root, lengths, theta = self.split(sig)
            lengths = self._len if self._len is not None else lengths
            self.model.positions_into(root, lengths, theta, self._buf)
            return self._buf.reshape(S, -1)
        root, lengths, theta = self.split(sig)
        return self.model.positions(root, lengths, theta).reshape(sig.shape[:-1] + (3 * skeleton.J,))

    def predict_random_walk(self, scale: float) -> None:
        """Adds the random-walk variance Q·scale (scale = dt · rate_ref) to P's diagonal, never beyond p0_ceiling.

        Directions the joints do not observe (e.g. how a twist splits between SPINE and NECK, a hand's roll) would
        otherwise grow without bound, spreading the sigma points over several radians where F is far from linear;
        observed directions have variances far below the ceiling, so for them this is the plain random walk.
        """
        q = self.Q.diagonal() * scale
        if _ukf_numba.AVAILABLE and self.P.dtype == np.float64:
            _ukf_numba.add_capped(self.P, self._diag, q, self.p0_ceiling)
            return
        d = self._diag
        self.P[d, d] += np.minimum(q, np.maximum(self.p0_ceiling - self.P[d, d], 0.0))

    def update_joints(
        self, z: np.ndarray, observed: np.ndarray, R_diag: np.ndarray, gate_chi2: float | None
    ) -> np.ndarray:
        """One gated update (UnscentedKalmanFilter.gated_update); one fused compiled kernel when available.

        z (60,) m, NaN allowed where not observed; observed (60,) bool; R_diag (60,) m². Returns (20,) bool used
        joints. The kernel sets x_prior and P_prior but not y, S and log_likelihood: after a compiled step they are
        empty and NaN (the numpy step, compiled=False, sets them).
        """
        gate = np.inf if gate_chi2 is None else float(gate_chi2)
        if self.compiled:
            x, P = self.x, self.P
            if not (x.dtype == np.float64 and x.flags.c_contiguous and x.flags.writeable):
                self.x = x = np.array(x, dtype=np.float64)
            if not (P.dtype == np.float64 and P.flags.c_contiguous and P.flags.writeable):
                self.P = P = np.array(P, dtype=np.float64)
            used = np.empty(skeleton.J, dtype=bool)
            self._begin_update()
            status = _ukf_numba.chain_step(
                x, P, z, observed, R_diag, self.kernel_weights, gate, self.fixed_lengths, self.n_len,
                self.model.rest, self.model.R_ref, km.STEP_TABLES, used,
            )  # fmt: skip
            if status == _ukf_numba.OK:
                self.log_likelihood = float("nan")
                return used
            # P or S not positive definite (x, P untouched): the numpy path below adds jitter.
        groups = (np.asarray(observed, dtype=bool) & np.isfinite(z)).reshape(-1, 3).all(axis=1)
        return self.gated_update(
            np.where(np.isfinite(z), z, 0.0), np.repeat(groups, 3), R_diag, gate, at_mean=self.innovation_at_mean
        )

    def run_frames(
        self,
        frames: FrameData,
        order: np.ndarray,
        q_steps: np.ndarray,
        span: tuple[int, int],
        gate_chi2: float | None,
        restart: tuple[np.ndarray, int] | None,
        run: np.ndarray,
        store: tuple[np.ndarray, np.ndarray] | None,
    ) -> tuple[int, int]:
        """Runs frames order[i0:i1] (span) of a pass in one compiled loop (_ukf_numba.run_frames), updating x, P,
        x_prior, P_prior and run (J,) int, the consecutive gated frames per joint; per frame: predict_random_walk
        (q_steps[i], none at i = 0), reacquire of joints gated in restart[1] consecutive frames (from restart[0],
        (T, 36)), update_joints, and x, P into store = (xs (T, n), Ps (T, n, n)) at row order[i].

        The same operations as calling those methods frame by frame (pipeline._run_pass). Needs self.compiled.
        Returns (i, gated): i = i1, or the first frame whose update the kernel declined (covariance not positive
        definite; that frame is predicted and re-acquired, and the caller updates it with update_joints);
        gated: joint samples the gate dropped.
        """
        if not self.compiled:
            raise RuntimeError("run_frames needs the compiled kernels (ChainFilter.compiled)")
        for name in ("x", "P"):
            a = getattr(self, name)
            if not (a.dtype == np.float64 and a.flags.c_contiguous and a.flags.writeable):
                setattr(self, name, np.array(a, dtype=np.float64))
        self.x_prior, self.P_prior = self.x.copy(), self.P.copy()
        start, n_frames = (np.zeros((1, N_ROOT + N_TH)), 0) if restart is None else restart
        xs, Ps = store if store is not None else (np.empty((0, self.dim_x)), np.empty((0, self.dim_x, self.dim_x)))
        gate = np.inf if gate_chi2 is None else float(gate_chi2)
        i, gated = _ukf_numba.run_frames(
            self.x, self.P, self.x_prior, self.P_prior, frames.as_tuple(), order, q_steps, span[0], span[1],
            (np.ascontiguousarray(self.Q.diagonal()), self._diag, self.p0_ceiling),
            (self.kernel_weights, gate, self.fixed_lengths, self.n_len, self.model.rest, self.model.R_ref,
             km.STEP_TABLES),
            (start, n_frames, _PLACING_TABLE), run, np.empty(skeleton.J, dtype=bool), xs, Ps,
        )  # fmt: skip
        self.y, self.S, self.log_likelihood = np.zeros(0), np.zeros((0, 0)), float("nan")
        return int(i), int(gated)

    def reacquire(self, joints: np.ndarray, start: np.ndarray) -> None:
        """Restarts the state entries that place `joints` from `start` (root (3) m + theta (33) rad, e.g. IK of the
        frame). Their covariance becomes the initial one (p0_ceiling) with no correlation to the rest of the state.
        """
        entries = np.unique(np.concatenate([_PLACING[j] for j in joints]))
        idx = np.where(entries < N_ROOT, entries, entries + self.dim_x - N_ROOT - N_TH)  # skip lengths in the state
        self.x[idx] = start[entries]
        self.P[idx, :] = 0.0
        self.P[:, idx] = 0.0
        self.P[idx, idx] = self.p0_ceiling[idx]


__all__ = ["ChainFilter", "FrameData", "state_dim"]
