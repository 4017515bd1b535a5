"""Joint-position error split into a bias part (each joint's mean error in the body frame) and a random part.

A Kinect's error is largely a systematic offset that moves with the body (a wrist measured 4 cm off along the
forearm stays so while the arm moves); no temporal filter sees it. Expressed in the body frame of the truth
(kinect_agent.body.angles.body_frame: left, up, forward), each joint's error over one recording is
    e_j(t) = R(t) (p̂_j(t) − p_j(t)),     m_j = mean_t e_j(t),
and the squared error splits exactly (R(t) is a rotation):
    Σ_t,j |p̂ − p|² = Σ_t,j |e_j(t) − m_j|² (random part: what a filter can remove) + T Σ_j |m_j|² (bias part).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from kinect_agent.body.angles import body_frame


@dataclass
class ErrorSums:
    """Squared-error sums over joint-frames (m²): total = random + bias; n joint-frames. Pool by adding."""

    total: float = 0.0
    random: float = 0.0
    bias: float = 0.0
    n: int = 0

    def add(self, other: ErrorSums) -> None:
        """Adds another recording's sums to these."""
        self.total += other.total
        self.random += other.random
        self.bias += other.bias
        self.n += other.n

    def rms_mm(self) -> dict[str, float | None]:
        """Returns {"rmse_mm", "random_mm", "bias_mm"}: each sqrt(sum / n) in mm, None with no joint-frames."""
        if not self.n:
            return {"rmse_mm": None, "random_mm": None, "bias_mm": None}
        return {
            "rmse_mm": 1e3 * float(np.sqrt(self.total / self.n)),
            "random_mm": 1e3 * float(np.sqrt(self.random / self.n)),
            "bias_mm": 1e3 * float(np.sqrt(self.bias / self.n)),
        }


def body_rotations(truth: np.ndarray) -> np.ndarray:
    """Returns R (T, 3, 3): rows are the truth's left, up and forward unit vectors (camera frame -> body frame).

    truth: (T, J, 3) m, camera frame, finite.
    """
    up, left, forward = body_frame(truth)
    return np.stack([left, up, forward], axis=-2)


def error_sums(estimate: np.ndarray, truth: np.ndarray) -> ErrorSums:
    """Returns the total, random and bias squared-error sums of one recording.

    estimate, truth: (T, J, 3) m, camera frame, finite (T ≥ 1). The bias of joint j is its mean error over the T
    frames expressed in the truth's body frame (body_rotations); the random part is what remains.
    """
    estimate, truth = np.asarray(estimate, dtype=float), np.asarray(truth, dtype=float)
    if estimate.shape != truth.shape or estimate.ndim != 3 or estimate.shape[-1] != 3:
        raise ValueError(f"expected estimate and truth of one shape (T, J, 3); got {estimate.shape}, {truth.shape}")
    err_body = np.einsum("tab,tjb->tja", body_rotations(truth), estimate - truth)  # (T, J, 3)
    mean = err_body.mean(axis=0)  # (J, 3)
    return ErrorSums(
        total=float(np.sum((estimate - truth) ** 2)),
        random=float(np.sum((err_body - mean) ** 2)),
        bias=float(len(truth) * np.sum(mean**2)),
        n=int(truth.shape[0] * truth.shape[1]),
    )


@dataclass
class JointErrorSums:
    """Per joint (J,), pooled over recordings: joint-frames n, squared-error sum sq (m²) and bias_sq (m²), the sum
    over recordings of n_r |mean body-frame error|² (the part a constant per recording and joint explains)."""

    n: np.ndarray
    sq: np.ndarray
    bias_sq: np.ndarray

    @classmethod
    def zeros(cls, n_joints: int) -> JointErrorSums:
        """Returns empty sums for n_joints joints."""
        return cls(np.zeros(n_joints), np.zeros(n_joints), np.zeros(n_joints))

    def add(self, estimate: np.ndarray, truth: np.ndarray, frame: np.ndarray | None = None) -> None:
        """Adds one recording: estimate, truth (T, J, 3) m, camera frame; NaN in either = not counted.

        frame: (T, J, 3) m, the positions whose body frame (body_rotations) the errors are expressed in, default
        truth (give the full mocap when truth is masked to the scored joints); frames without one are not counted.
        """
        R = body_rotations(truth if frame is None else frame)  # (T, 3, 3), NaN where the trunk joints are missing
        self.add_body(np.einsum("tab,tjb->tja", R, estimate - truth))

    def add_body(self, err: np.ndarray) -> None:
        """Adds one recording's errors err (T, J, 3) m, already in a body frame; NaN = not counted."""
        ok = np.all(np.isfinite(err), axis=-1)
        z = np.where(ok[..., None], err, 0.0)
        n = ok.sum(axis=0)
        self.n += n
        self.sq += np.sum(z**2, axis=(0, 2))
        self.bias_sq += np.sum(z.sum(axis=0) ** 2, axis=-1) / np.maximum(n, 1)

    def merge(self, other: JointErrorSums) -> None:
        """Adds the sums of other (the same joints)."""
        self.n += other.n
        self.sq += other.sq
        self.bias_sq += other.bias_sq

    def pooled(self) -> dict[str, float]:
        """Returns {"rmse_mm", "bias_mm", "random_mm", "n"} over every joint-frame."""
        n = self.n.sum()
        rmse2, bias2 = self.sq.sum() / n, self.bias_sq.sum() / n
        return {"rmse_mm": 1e3 * float(np.sqrt(rmse2)), "bias_mm": 1e3 * float(np.sqrt(bias2)),
                "random_mm": 1e3 * float(np.sqrt(max(rmse2 - bias2, 0.0))), "n": int(n)}  # fmt: skip

    def rms_mm(self) -> dict[str, np.ndarray]:
        """Returns {"rmse_mm", "bias_mm", "random_mm", "n"}: (J,) each; NaN where a joint has no joint-frames."""
        with np.errstate(invalid="ignore", divide="ignore"):
            rmse2, bias2 = self.sq / self.n, self.bias_sq / self.n
        return {
            "rmse_mm": 1e3 * np.sqrt(rmse2),
            "bias_mm": 1e3 * np.sqrt(bias2),
            "random_mm": 1e3 * np.sqrt(np.maximum(rmse2 - bias2, 0.0)),
            "n": self.n.astype(int),
        }
